// Reading query files: the public format, numbers beyond 64 bits, and every malformed input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "drape/ccd_eval/query_file.h"
#include "../temp_root.h"

using namespace drape;
using namespace drape::ccd;
namespace fs = std::filesystem;

namespace {

// A file under <tmp>/<kind folder>/name with the given text.
fs::path write_file(const std::string& folder, const std::string& name, const std::string& text) {
  const fs::path dir = drape::testing::temp_root("query_file_test") / folder;
  fs::create_directories(dir);
  const fs::path path = dir / name;
  std::ofstream(path) << text;
  return path;
}

std::string rows(int count, const std::string& row = "0,1,0,1,0,1,0") {
  std::string text;
  for (int i = 0; i < count; ++i) text += row + "\n";
  return text;
}

// The error message for a malformed file, or "" when it reads.
std::string error_of(const fs::path& path) {
  try {
    read_query_file(path);
  } catch (const QueryFileError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(QueryFile, ReadsTheBundledFiles) {
  const QueryFile f = read_query_file(DRAPE_TEST_DATA "/ccd-queries/unit-tests/edge-edge/data_0_0.csv");
  EXPECT_EQ(f.kind, QueryKind::EdgeEdge);
  EXPECT_EQ(f.queries.size(), 54u);
  EXPECT_EQ(std::count(f.truth.begin(), f.truth.end(), true), 21);
}

TEST(QueryFile, KindFromFolderOrOverride) {
  const auto vf = write_file("vertex-face", "a.csv", rows(8));
  EXPECT_EQ(read_query_file(vf).kind, QueryKind::VertexFace);
  EXPECT_EQ(read_query_file(vf, QueryKind::EdgeEdge).kind, QueryKind::EdgeEdge);
  const auto none = write_file("elsewhere", "a.csv", rows(8));
  EXPECT_NE(error_of(none).find("--kind"), std::string::npos);
  EXPECT_EQ(read_query_file(none, QueryKind::VertexFace).queries.size(), 1u);
}

TEST(QueryFile, NumbersBeyondSixtyFourBitsAreExact) {
  // 2^70 / 2^70 = 1 and (2^64 + 2) / 2^65 = 0.5 + 2^-64: exactly representable doubles.
  const std::string big = "1180591620717411303424,1180591620717411303424,18446744073709551618,36893488147419103232,-3,4,1";
  const auto path = write_file("edge-edge", "big.csv", rows(8, big));
  const QueryFile f = read_query_file(path);
  EXPECT_EQ(f.queries[0].start[0].x(), 1.0);
  EXPECT_EQ(f.queries[0].start[0].y(), 0.5 + 0x1p-64);
  EXPECT_EQ(f.queries[0].start[0].z(), -0.75);
  EXPECT_TRUE(f.truth[0]);
}

TEST(QueryFile, RoundsToTheNearestDouble) {
  // 1/3 is not representable: the nearest double, as the compiler rounds it.
  const auto path = write_file("edge-edge", "third.csv", rows(8, "1,3,-2,3,0,1,0"));
  const QueryFile f = read_query_file(path);
  EXPECT_EQ(f.queries[0].start[0].x(), 1.0 / 3.0);
  EXPECT_EQ(f.queries[0].start[0].y(), -2.0 / 3.0);
}

TEST(QueryFile, MalformedFilesNameTheFileAndLine) {
  struct Case {
    std::string name, text, expected;
  };
  const std::vector<Case> cases = {
      {"columns.csv", rows(3) + "0,1,0,1,0,1\n" + rows(4), ":4: expected 7 comma-separated integers"},
      {"extra.csv", rows(5) + "0,1,0,1,0,1,0,9\n" + rows(2), ":6: expected 7"},
      {"count.csv", rows(12), ":12: the file has 12 rows, not a multiple of 8"},
      {"zero.csv", rows(2) + "1,0,0,1,0,1,0\n" + rows(5), ":3: column 2: zero denominator"},
      {"text.csv", rows(6) + "0,1,abc,1,0,1,0\n" + rows(1), ":7: column 3: expected an integer, found 'abc'"},
      {"float.csv", "0.5,1,0,1,0,1,0\n" + rows(7), ":1: column 1: expected an integer, found '0.5'"},
      {"truth.csv", rows(7) + "0,1,0,1,0,1,2\n", ":8: column 7: expected the truth value 0 or 1"},
      {"mixed.csv", rows(4) + rows(4, "0,1,0,1,0,1,1"), ":5: column 7: the 8 rows of a query must share"},
      {"blank.csv", rows(3) + "\n" + rows(5), ":4: empty line"},
      {"empty.csv", "", ":1: the file is empty"},
      {"empty_field.csv", rows(7) + "0,1,0,1,0,,0\n", ":8: column 6: expected an integer, found ''"},
      {"huge.csv", "1" + std::string(400, '0') + ",1,0,1,0,1,0\n" + rows(7), ":1: column 1: value out of the range of a double"},
  };
  for (const Case& c : cases) {
    const auto path = write_file("vertex-face", c.name, c.text);
    const std::string message = error_of(path);
    EXPECT_NE(message.find(path.string()), std::string::npos) << c.name << ": " << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.name << ": " << message;
  }
  EXPECT_NE(error_of("/nonexistent/vertex-face/x.csv").find("no such query file"), std::string::npos);
}

TEST(QueryFile, TrailingBlankLinesAndWindowsLineEndsAreAccepted) {
  std::string text;
  for (int i = 0; i < 8; ++i) text += "0,1,0,1,0,1,0\r\n";
  const auto path = write_file("vertex-face", "crlf.csv", text + "\n\n");
  EXPECT_EQ(read_query_file(path).queries.size(), 1u);
}

// Written files read back to the same doubles and truths: the shared file, and doubles from
// subnormal to huge with every bit of the mantissa in use.
TEST(QueryFile, WrittenFilesReadBackExactly) {
  QueryFile original = read_query_file(DRAPE_TEST_DATA "/ccd-queries/unit-tests/edge-edge/data_0_0.csv");
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> mantissa(-1, 1);
  // From subnormal doubles to below MAX_QUERY_COORDINATE (2^295 < 1e90).
  std::uniform_int_distribution<int> exponent(-1060, 295);
  for (int q = 0; q < 50; ++q) {
    Query query;
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) {
        query.start[i][k] = std::ldexp(mantissa(rng), exponent(rng));
        query.end[i][k] = std::ldexp(mantissa(rng), exponent(rng));
      }
    original.queries.push_back(query);
    original.truth.push_back(q % 3 == 0);
  }
  const fs::path path = write_file("edge-edge", "written.csv", "");
  write_query_file(path, original);
  const QueryFile back = read_query_file(path);
  ASSERT_EQ(back.queries.size(), original.queries.size());
  EXPECT_EQ(back.truth, original.truth);
  for (std::size_t q = 0; q < back.queries.size(); ++q)
    for (int i = 0; i < 4; ++i) {
      EXPECT_EQ(back.queries[q].start[i], original.queries[q].start[i]) << "query " << q;
      EXPECT_EQ(back.queries[q].end[i], original.queries[q].end[i]) << "query " << q;
    }
  EXPECT_NE(error_of(fs::path("/nonexistent-folder/edge-edge/x.csv")), "");
  EXPECT_THROW(write_query_file("/nonexistent-folder/edge-edge/x.csv", original), QueryFileError);
}
