// Internals shared by the campaign's source files (campaign.cc, campaign_plan.cc,
// campaign_table.cc); not part of the public API.
#ifndef IMPACTDIC_SRC_PIPELINE_CAMPAIGN_INTERNAL_H_
#define IMPACTDIC_SRC_PIPELINE_CAMPAIGN_INTERNAL_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/campaign.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic::campaign_internal {

// Campaign-level files (written at the end, one generation of the campaign folder).
inline constexpr const char* kCampaignCsv = "campaign.csv";
inline constexpr const char* kCampaignH5 = "campaign.h5";
inline constexpr const char* kRegressionJson = "regression.json";
// In each test's folder: its campaign.csv row, what resuming reads back.
inline constexpr const char* kRowCsv = "campaign_row.csv";
// The comparison figures: file name, title, x label, y label, measured and modelled column.
struct ComparisonSpec {
  const char* file;
  const char* title;
  const char* x_label;
  const char* y_label;
  const char* observed;   // A campaign.csv column.
  const char* predicted;  // A campaign.csv column.
  // A relation between two quantities, not a model against a measurement (no 1:1 line), drawn
  // only when a test has both values: the wave figures need base force channels, which most
  // campaigns do not record.
  bool relation = false;
};
const std::vector<ComparisonSpec>& ComparisonSpecs();
// Every file name the campaign level writes (a test may not be named so).
std::vector<std::string> CampaignFileNames();

// 64-bit FNV-1a of the bytes, as 16 hex digits (stable across machines and runs).
std::string ContentHash(const std::string& bytes);
// The same hash fed in pieces: ContentHasher h; h.Add(a); h.Add(b); h.Hex() == ContentHash(a + b).
class ContentHasher {
 public:
  void Add(std::string_view bytes);
  std::string Hex() const;

 private:
  std::uint64_t h_ = 14695981039346656037ull;  // FNV-1a 64 offset basis.
};

// What resuming compares for a scene-file test besides the plan's hash (the scene file's bytes):
// every input file the scene reads -- each file of inputs.frames (io FrameSourceFiles: the glob's
// or the folder's images, the video, a camera file with its companion: a .cih/.cihx and its
// .mraw), or inputs.frame_files when given; inputs.sensor, inputs.calibration, inputs.truth,
// dic.mask -- by its path as the scene resolves it, its size and a hash of its bytes (not its
// mtime: a copy or a `touch` keeps the results, a replaced or edited file re-runs the test). A
// file that cannot be read or listed (a missing .mraw or .cih) hashes as such (the test then
// fails and is never resumed). Reads every input once: about 1 s per GB on one core.
std::string SceneInputsHash(const Scene& scene);
// Version() and GitRevision(): a result made by another build is not reused.
std::string ToolVersion();

// campaign.csv: the column names and one row's cells; RowFromCells is the exact inverse (numbers
// are written in their shortest form that reads back to the same double).
std::vector<std::string> RowColumnNames();
std::vector<std::string> RowCells(const CampaignRow& row);
// Reads every row of a campaign.csv (or campaign_row.csv). Error naming the file if a column is
// missing or a cell malformed.
std::vector<CampaignRow> ReadRows(const std::string& csv_path);
void WriteRows(const std::string& csv_path, const std::vector<CampaignRow>& rows);

// Fits Eq. 4 over the rows with a usable m_add,max (marking the others excluded), computes the
// comparison fits, and writes campaign.csv, campaign.h5, regression.json and (options.figures)
// the figures into `folder` (a staging folder). `plan_text` goes into campaign.h5's provenance.
void FitAndWrite(CampaignSummary* summary, const CampaignOptions& options,
                 const std::string& folder, const std::string& plan_text);

// The campaign folder's generation for the campaign-level files: it replaces those and keeps the
// test folders (and anything else impactdic wrote there), hard-linked. `force`: also replace a
// folder another kind of command wrote (OutputGenerationOptions::force).
OutputGenerationOptions CampaignLevelGeneration(const std::string& command, bool force);

}  // namespace impactdic::campaign_internal

#endif  // IMPACTDIC_SRC_PIPELINE_CAMPAIGN_INTERNAL_H_
