// CsvRowWriter and AtomicStreamWriter: a long table written as it is formatted
// gives the bytes WriteCsvRows gives, appears only when complete, and keeps the promise of a full
// disk (docs/reliability.md, section 1) when the disk fills up in the middle of the rows, long
// before the commit.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../reliability/small_disk.h"
#include "impactdic/core/error.h"
#include "impactdic/io/csv.h"
#include "test_dir.h"

namespace impactdic {
namespace {

const std::vector<std::string> kNames = {"frame", "u_px", "status"};

// Row k of the test table (about 30 bytes).
std::array<std::string, 3> TableRow(int k) {
  return {std::to_string(k / 100), std::to_string(k * 0.001), k % 7 ? "converged" : "lost"};
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// 100000 rows (3 MB, several of the writer's 1 MiB blocks): the header line, then the cells of
// each row joined by commas, one line per row (what WriteCsvRows wrote from its whole text
// before), and nothing under the final name before Commit().
TEST(CsvRowWriter, WritesTheRowsAsLinesAndAppearsOnlyOnCommit) {
  const TestDir dir;
  constexpr int kRows = 100000;
  std::string expected = "frame,u_px,status\n";
  {
    CsvRowWriter out(dir.File("streamed.csv"), kNames);
    for (int k = 0; k < kRows; ++k) {
      const auto row = TableRow(k);
      expected += row[0] + "," + row[1] + "," + row[2] + "\n";
      out.Row(row);
    }
    EXPECT_FALSE(std::filesystem::exists(dir.File("streamed.csv")));
    out.Commit();
  }
  EXPECT_GT(expected.size(), 2 * AtomicStreamWriter::kBlockBytes);
  EXPECT_EQ(ReadAll(dir.File("streamed.csv")), expected);
}

// The disk fills up at a block in the middle of the rows: Error naming the file and "no space
// left", the temporary removed, the earlier file of that name kept byte for byte.
TEST(CsvRowWriter, FullDiskInTheMiddleOfTheRowsKeepsTheEarlierFile) {
  std::string why_not;
  auto disk = SmallDisk::Mount(std::size_t{4} << 20, &why_not);
  if (!disk) GTEST_SKIP() << "disk-full tests skipped: " << why_not;
  const std::string path = disk->File("rows.csv");
  std::ofstream(path) << "frame,u_px,status\n1,0.5,converged\n";
  const std::string earlier = ReadAll(path);
  ASSERT_TRUE(disk->LeaveFree(std::size_t{3} << 19));  // 1.5 MiB: room for one block, not two.
  int rows_written = 0;
  try {
    CsvRowWriter out(path, kNames);
    for (int k = 0; k < 200000; ++k, ++rows_written) out.Row(TableRow(k));
    out.Commit();
    FAIL() << "no error writing 6 MB into 1.5 MiB";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no space left"), std::string::npos) << e.what();
  }
  EXPECT_LT(rows_written, 200000);  // Failed while writing the rows, not at the commit.
  EXPECT_TRUE(disk->TemporaryFiles().empty())
      << "temporary file left: " << disk->TemporaryFiles().front();
  EXPECT_EQ(ReadAll(path), earlier);
}

}  // namespace
}  // namespace impactdic
