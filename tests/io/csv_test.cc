#include "impactdic/io/csv.h"

#include <gtest/gtest.h>

#include <cmath>

#include "impactdic/core/error.h"
#include "test_dir.h"

namespace impactdic {
namespace {

std::string ReadError(const std::string& path, const CsvReadOptions& options = {}) {
  try {
    ReadCsv(path, options);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Csv, ReadsColumnsByName) {
  TestDir dir;
  const auto path =
      dir.Write("a.csv", "# comment\ntime_s, accel_g ,exposure\n0,1.5,0\n4e-5,-2,1\r\n");
  CsvReadOptions opts;
  opts.required_columns = {"time_s", "accel_g"};
  opts.increasing_column = "time_s";
  const CsvTable t = ReadCsv(path, opts);
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.Column("accel_g")[1], -2);
  EXPECT_EQ(t.Column("time_s")[1], 4e-5);
  EXPECT_TRUE(t.Has("exposure"));
}

TEST(Csv, MalformedNumberNamesFileLineAndColumn) {
  TestDir dir;
  const auto path = dir.Write("b.csv", "t,a\n0,1\n1,x2\n");
  const std::string msg = ReadError(path);
  EXPECT_NE(msg.find("b.csv:3:2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'x2'"), std::string::npos) << msg;
}

TEST(Csv, NanIsRejectedUnlessAllowed) {
  TestDir dir;
  const auto path = dir.Write("c.csv", "t,a\n0,1\n1,nan\n2,\n");
  const std::string msg = ReadError(path);
  EXPECT_NE(msg.find("c.csv:3:2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("a finite number"), std::string::npos) << msg;
  CsvReadOptions opts;
  opts.allow_non_finite = true;
  const CsvTable t = ReadCsv(path, opts);
  EXPECT_TRUE(std::isnan(t.Column("a")[1]));
  EXPECT_TRUE(std::isnan(t.Column("a")[2]));
}

TEST(Csv, NonMonotonicTimeRaggedRowsAndMissingColumns) {
  TestDir dir;
  CsvReadOptions opts;
  opts.increasing_column = "t";
  const std::string msg = ReadError(dir.Write("d.csv", "t,a\n0,1\n# note\n2,1\n1,1\n"), opts);
  EXPECT_NE(msg.find("d.csv:5:1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("strictly increasing"), std::string::npos) << msg;
  const std::string ragged = ReadError(dir.Write("e.csv", "t,a\n0,1,3\n"));
  EXPECT_NE(ragged.find("e.csv:2"), std::string::npos) << ragged;
  CsvReadOptions need;
  need.required_columns = {"accel_g"};
  const std::string missing = ReadError(dir.Write("f.csv", "t,a\n0,1\n"), need);
  EXPECT_NE(missing.find("'accel_g'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("columns are t, a"), std::string::npos) << missing;
  EXPECT_NE(ReadError(dir.File("none.csv")).find("none.csv"), std::string::npos);
  EXPECT_NE(ReadError(dir.Write("g.csv", "1,2\n")).find("header"), std::string::npos);
}

TEST(Csv, WriteThenReadRoundTrip) {
  TestDir dir;
  const std::string path = dir.File("out.csv");
  WriteCsv(path, {"x", "y"}, {{1, 2, 3}, {0.1, std::nan(""), 1e-9}});
  CsvReadOptions opts;
  opts.allow_non_finite = true;
  const CsvTable t = ReadCsv(path, opts);
  EXPECT_EQ(t.names, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(t.Column("x")[2], 3);
  EXPECT_TRUE(std::isnan(t.Column("y")[1]));
  EXPECT_DOUBLE_EQ(t.Column("y")[2], 1e-9);
}

}  // namespace
}  // namespace impactdic

namespace impactdic {
namespace {

TEST(Csv, TextColumnsAreKeptAsText) {
  TestDir dir;
  CsvReadOptions opts;
  opts.text_columns = {"scene"};
  opts.increasing_column = "t";
  const CsvTable t = ReadCsv(dir.Write("h.csv", "scene,t,a\nt01,0,1\nt02,1,2\n"), opts);
  EXPECT_EQ(t.names, (std::vector<std::string>{"t", "a"}));
  EXPECT_EQ(t.TextColumn("scene")[1], "t02");
  EXPECT_EQ(t.Column("a")[1], 2);
  const std::string msg = ReadError(dir.Write("i.csv", "scene,t,a\nx,1,1\ny,0,1\n"), opts);
  EXPECT_NE(msg.find("i.csv:3:2"), std::string::npos) << msg;
  const std::string bad = ReadError(dir.Write("j.csv", "scene,t,a\nx,0,oops\n"), opts);
  EXPECT_NE(bad.find("j.csv:2:3"), std::string::npos) << bad;
}

}  // namespace
}  // namespace impactdic
