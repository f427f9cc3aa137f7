// The PLY check (ply_check.h): the header parsed into elements and properties, then each
// element's rows walked without building anything.
#include "ply_check.h"

#include <charconv>
#include <cstdint>
#include <cstring>
#include <map>
#include <vector>

#include "drape/core/mesh_io.h"

namespace drape {
namespace {

// A list longer than this is refused (a polygon of 65,536 corners is no cloth).
constexpr std::uint64_t MAX_LIST_LENGTH = 65536;

// Byte sizes of the PLY scalar types.
const std::map<std::string_view, int>& type_sizes() {
  static const std::map<std::string_view, int> sizes = {
      {"char", 1},  {"uchar", 1},  {"int8", 1},  {"uint8", 1},  {"short", 2},   {"ushort", 2},  {"int16", 2},   {"uint16", 2},
      {"int", 4},   {"uint", 4},   {"int32", 4}, {"uint32", 4}, {"float", 4},   {"float32", 4}, {"double", 8},  {"float64", 8}};
  return sizes;
}

bool is_float_type(std::string_view t) { return t == "float" || t == "float32" || t == "double" || t == "float64"; }
bool is_signed_type(std::string_view t) { return t == "char" || t == "int8" || t == "short" || t == "int16" || t == "int" || t == "int32"; }

struct Property {
  std::string_view name;
  std::string_view type;        // scalar type, or the list's item type
  std::string_view count_type;  // empty: not a list
};

struct Element {
  std::string_view name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

std::vector<std::string_view> words_of(std::string_view line) {
  std::vector<std::string_view> words;
  for (std::size_t i = 0; i < line.size();) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) words.push_back(line.substr(i, j - i));
    i = j;
  }
  return words;
}

// The next line from pos (without its '\r\n' or '\n'); false at the end of the data.
bool next_line(std::string_view data, std::size_t& pos, std::string_view& line) {
  if (pos >= data.size()) return false;
  std::size_t end = data.find('\n', pos);
  if (end == std::string_view::npos) end = data.size();
  line = data.substr(pos, end - pos);
  pos = end + 1;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return true;
}

template <class T>
bool parse_whole(std::string_view word, T& value) {
  if (!word.empty() && word[0] == '+') word.remove_prefix(1);
  const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
  return error == std::errc() && end == word.data() + word.size();
}

class Checker {
 public:
  Checker(std::string_view data, const std::string& name) : data_(data), name_(name) {}

  void run() {
    header();
    std::uint64_t vertices = 0;
    for (const Element& e : elements_)
      if (e.name == "vertex") vertices = e.count;
    for (const Element& e : elements_) {
      for (std::uint64_t row = 0; row < e.count; ++row) {
        row_ = row;
        element_ = &e;
        if (ascii_) ascii_row(e, vertices);
        else binary_row(e, vertices);
      }
    }
  }

 private:
  [[noreturn]] void header_error(const std::string& what) const {
    throw MeshFileError(name_ + ": PLY header line " + std::to_string(line_number_) + ": " + what);
  }
  [[noreturn]] void row_error(const std::string& what) const {
    throw MeshFileError(name_ + ": PLY element " + std::string(element_->name) + " row " + std::to_string(row_) + ": " + what);
  }

  void header() {
    bool format = false;
    std::string_view line;
    while (true) {
      ++line_number_;
      if (!next_line(data_, pos_, line) || pos_ > data_.size()) header_error("expected a line; the header ends without end_header");
      for (const char c : line)
        if (!(c == ' ' || c == '\t' || (c > ' ' && c < 127))) header_error("expected printable text");
      const auto words = words_of(line);
      const std::string_view first = words.empty() ? std::string_view() : words[0];
      if (line_number_ == 1) {
        if (words.size() != 1 || first != "ply") header_error("expected 'ply'");
      } else if (first == "comment" || first == "obj_info") {
      } else if (first == "format") {
        if (words.size() != 3 || (words[1] != "ascii" && words[1] != "binary_little_endian" && words[1] != "binary_big_endian"))
          header_error("expected 'format ascii|binary_little_endian|binary_big_endian VERSION'");
        ascii_ = words[1] == "ascii";
        big_endian_ = words[1] == "binary_big_endian";
        format = true;
      } else if (first == "element") {
        Element e;
        if (words.size() != 3 || !parse_whole(words[2], e.count)) header_error("expected 'element NAME COUNT'");
        // Every row takes a byte at least: a count beyond the file's size is a lie.
        if (e.count > data_.size()) header_error("an element count larger than the file (" + std::string(words[2]) + ")");
        e.name = words[1];
        elements_.push_back(e);
      } else if (first == "property") {
        if (elements_.empty()) header_error("a property before any element");
        const auto& types = type_sizes();
        if (words.size() == 5 && words[1] == "list" && types.count(words[2]) && types.count(words[3]) && !is_float_type(words[2]))
          elements_.back().properties.push_back({words[4], words[3], words[2]});
        else if (words.size() == 3 && types.count(words[1]))
          elements_.back().properties.push_back({words[2], words[1], {}});
        else
          header_error("expected 'property TYPE NAME' or 'property list INTEGER_TYPE TYPE NAME'");
      } else if (first == "end_header") {
        if (words.size() != 1) header_error("expected 'end_header' alone on its line");
        if (!format) header_error("end_header before any format line");
        return;
      } else {
        header_error("expected format, comment, obj_info, element, property or end_header");
      }
    }
  }

  static bool is_face_indices(const Element& e, const Property& p) {
    return e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index");
  }

  void ascii_row(const Element& e, std::uint64_t vertices) {
    std::string_view line;
    do {
      if (!next_line(data_, pos_, line)) row_error("expected a row, found the end of the file");
    } while (words_of(line).empty() && !e.properties.empty());
    const auto words = words_of(line);
    std::size_t w = 0;
    const auto number = [&](std::string_view type, bool index) {
      if (w >= words.size()) row_error("expected more numbers on the row");
      const std::string_view word = words[w++];
      if (is_float_type(type)) {
        double v = 0;
        if (!parse_whole(word, v)) row_error("expected a number, found '" + std::string(word) + "'");
        return std::int64_t(0);
      }
      std::int64_t v = 0;
      if (!parse_whole(word, v)) row_error("expected an integer, found '" + std::string(word) + "'");
      if (index && (v < 0 || std::uint64_t(v) >= vertices)) row_error("a vertex index out of range (" + std::string(word) + ")");
      return v;
    };
    for (const Property& p : e.properties) {
      if (p.count_type.empty()) {
        number(p.type, false);
        continue;
      }
      const std::int64_t length = number(p.count_type, false);
      if (length < 0 || std::uint64_t(length) > MAX_LIST_LENGTH) row_error("a list length out of range");
      for (std::int64_t i = 0; i < length; ++i) number(p.type, is_face_indices(e, p));
    }
    if (w != words.size()) row_error("expected " + std::to_string(w) + " numbers on the row, found " + std::to_string(words.size()));
  }

  // An integer of the given type at pos_, in the file's byte order.
  std::int64_t read_integer(std::string_view type) {
    const int size = type_sizes().at(type);
    if (pos_ + std::size_t(size) > data_.size()) row_error("the file ends inside the row");
    std::uint64_t bits = 0;
    for (int i = 0; i < size; ++i) {
      const auto byte = static_cast<unsigned char>(data_[pos_ + std::size_t(big_endian_ ? i : size - 1 - i)]);
      bits = (bits << 8) | byte;
    }
    pos_ += std::size_t(size);
    if (is_signed_type(type) && size < 8 && (bits >> (8 * size - 1)) != 0) return std::int64_t(bits) - (std::int64_t(1) << (8 * size));
    return std::int64_t(bits);
  }

  void binary_row(const Element& e, std::uint64_t vertices) {
    for (const Property& p : e.properties) {
      const auto size = std::size_t(type_sizes().at(p.type));
      if (p.count_type.empty()) {
        if (pos_ + size > data_.size()) row_error("the file ends inside the row");
        pos_ += size;
        continue;
      }
      const std::int64_t length = read_integer(p.count_type);
      if (length < 0 || std::uint64_t(length) > MAX_LIST_LENGTH) row_error("a list length out of range");
      if (!is_face_indices(e, p) || is_float_type(p.type)) {
        if (pos_ + size * std::size_t(length) > data_.size()) row_error("the file ends inside the row");
        pos_ += size * std::size_t(length);
        continue;
      }
      for (std::int64_t i = 0; i < length; ++i) {
        const std::int64_t index = read_integer(p.type);
        if (index < 0 || std::uint64_t(index) >= vertices) row_error("a vertex index out of range");
      }
    }
  }

  std::string_view data_;
  const std::string& name_;
  std::size_t pos_ = 0;
  int line_number_ = 0;
  bool ascii_ = true, big_endian_ = false;
  std::vector<Element> elements_;
  const Element* element_ = nullptr;
  std::uint64_t row_ = 0;
};

}  // namespace

void check_ply(std::string_view data, const std::string& name) { Checker(data, name).run(); }

}  // namespace drape
