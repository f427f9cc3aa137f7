#pragma once
// A scene file's JSON node with its path in the file, for messages that say where (scene.cpp
// and scene_material.cpp read scenes with it). Private to core.
#include "drape/core/scene.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

namespace drape::scene_json {

using json = nlohmann::json;

inline std::string format_number(Scalar x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

inline std::string describe(const json& value) {
  std::string text = value.dump();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text;
}

// A JSON node with its path in the file, for messages that say where.
class Node {
 public:
  Node(const json& value, std::string path, const std::filesystem::path& file)
      : value_(value), path_(std::move(path)), file_(file) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError(file_.string() + ": " + (path_.empty() ? "/" : path_) + ": " + what);
  }
  const std::string& path() const { return path_; }
  const json& raw() const { return value_; }

  // Only these keys (and "comment") may appear.
  void allow(std::initializer_list<const char*> keys) const {
    if (!value_.is_object()) fail("expected an object, found " + describe(value_));
    std::set<std::string> allowed(keys.begin(), keys.end());
    allowed.insert("comment");
    for (const auto& [key, v] : value_.items()) {
      if (allowed.count(key)) continue;
      std::string list;
      for (const auto& k : keys) list += std::string(list.empty() ? "" : ", ") + k;
      Node(v, path_ + "/" + key, file_).fail("unknown key (expected one of: " + list + ")");
    }
  }
  bool has(const char* key) const { return value_.is_object() && value_.contains(key); }
  Node at(const char* key) const {
    if (!has(key)) fail(std::string("missing the required key '") + key + "'");
    return Node(value_.at(key), path_ + "/" + key, file_);
  }
  Node at(std::size_t index) const { return Node(value_.at(index), path_ + "/" + std::to_string(index), file_); }
  std::size_t size() const { return value_.size(); }

  std::vector<Node> array(std::size_t min_size = 0) const {
    if (!value_.is_array()) fail("expected an array, found " + describe(value_));
    if (value_.size() < min_size) fail("expected at least " + std::to_string(min_size) + " entries");
    std::vector<Node> out;
    for (std::size_t i = 0; i < value_.size(); ++i) out.push_back(at(i));
    return out;
  }
  Scalar number() const {
    if (!value_.is_number()) fail("expected a number, found " + describe(value_));
    const Scalar x = value_.get<Scalar>();
    if (!std::isfinite(x)) fail("expected a finite number");
    return x;
  }
  Scalar number_in(Scalar lo, Scalar hi, const char* range) const {
    const Scalar x = number();
    if (!(x >= lo && x <= hi)) fail(std::string("expected a number ") + range + ", found " + describe(value_));
    return x;
  }
  Scalar positive() const {
    const Scalar x = number();
    if (!(x > 0)) fail("expected a number > 0, found " + describe(value_));
    return x;
  }
  Scalar non_negative() const { return number_in(0, std::numeric_limits<Scalar>::max(), ">= 0"); }
  /// A number in (0, most] (or [0, most] with zero allowed), most given with its unit.
  Scalar up_to(Scalar most, const std::string& unit, bool zero_allowed = false) const {
    const Scalar x = number();
    if (!((zero_allowed ? x >= 0 : x > 0) && x <= most))
      fail(std::string("expected a number ") + (zero_allowed ? ">= 0" : "> 0") + " and at most " + format_number(most) +
           (unit.empty() ? "" : " " + unit) + ", found " + describe(value_));
    return x;
  }
  int integer_in(int lo, int hi) const {
    if (!value_.is_number_integer()) fail("expected an integer, found " + describe(value_));
    const auto x = value_.get<long long>();
    if (x < lo || x > hi)
      fail("expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi) + ", found " + describe(value_));
    return int(x);
  }
  bool boolean() const {
    if (!value_.is_boolean()) fail("expected true or false, found " + describe(value_));
    return value_.get<bool>();
  }
  std::string string() const {
    if (!value_.is_string()) fail("expected a string, found " + describe(value_));
    return value_.get<std::string>();
  }
  std::string one_of(std::initializer_list<const char*> choices) const {
    const std::string s = string();
    std::string list;
    for (const auto& c : choices) {
      if (s == c) return s;
      list += std::string(list.empty() ? "" : ", ") + "'" + c + "'";
    }
    fail("expected one of " + list + ", found '" + s + "'");
  }
  Vec3 vec3() const {
    if (!value_.is_array() || value_.size() != 3) fail("expected an array of 3 numbers, found " + describe(value_));
    return Vec3(at(std::size_t(0)).number(), at(1).number(), at(2).number());
  }
  // A vector whose every coordinate is within bound (what the bound is, for the message).
  Vec3 vec3_within(Scalar bound, const char* unit) const {
    const Vec3 v = vec3();
    if (!(v.cwiseAbs().maxCoeff() <= bound))
      fail("expected coordinates within +-" + format_number(bound) + " " + unit + ", found " + describe(value_));
    return v;
  }
  Vec2 vec2() const {
    if (!value_.is_array() || value_.size() != 2) fail("expected an array of 2 numbers, found " + describe(value_));
    return Vec2(at(std::size_t(0)).number(), at(1).number());
  }
  std::filesystem::path file_path() const {
    const std::filesystem::path p = string();
    return p.is_absolute() ? p : file_.parent_path() / p;
  }

 private:
  const json& value_;
  std::string path_;
  const std::filesystem::path& file_;
};

// The material section of a cloth (the cloth is a grid or a mesh) read into material, which
// holds the defaults (scene_material.cpp).
void read_material(const Node& m, bool grid, Material& material);

}  // namespace drape::scene_json
