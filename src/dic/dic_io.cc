#include "impactdic/dic/dic_io.h"

#include <fmt/format.h>
#include <malloc.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <opencv2/core.hpp>
#include <type_traits>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/results_layout.h"

namespace impactdic {
namespace {

std::string Number(double v) {
  if (std::isnan(v)) return "nan";
  return fmt::format("{:.6f}", v);
}

// A dimensionless gradient: 9 significant digits (strains of 1e-5 and below keep theirs).
std::string Ratio(double v) {
  if (std::isnan(v)) return "nan";
  return fmt::format("{:.9g}", v);
}

// The frame number of image `index` (0 = the first reference): from its file name when the
// names are one numbered series, else the index itself.
long long FrameLabel(const DicResult& result, int index) {
  const auto k = static_cast<std::size_t>(index);
  return k < result.frame_numbers.size() ? result.frame_numbers[k] : index;
}

}  // namespace

bool IsValidStatus(SubsetStatus status) { return status == SubsetStatus::kConverged; }
static_assert(static_cast<int>(SubsetStatus::kConverged) == results_layout::kValidStatusCode);

bool FailsInReference(SubsetStatus status) {
  return status == SubsetStatus::kMasked || status == SubsetStatus::kSingularHessian ||
         status == SubsetStatus::kLowContrast || status == SubsetStatus::kSaturated;
}

namespace {

constexpr std::size_t kTrimRows = 16;  // Rows released between two malloc_trim calls.

// MakeDicResultsTable; a DicResult passed as non-const has each frame's arrays released once
// they are in the table, so that the results are in memory once (plus a frame), not twice.
template <typename Result>
DicResultsTable MakeTable(Result& result, const DicOptions& options, int first_frame) {
  DicResultsTable t;
  t.first_frame = first_frame;  // -1: unknown (the indices are then those of the images given).
  first_frame = std::max(first_frame, 0);
  const std::size_t n = result.positions.size(), rows = result.frames.size() + 1;
  t.layout_version = results_layout::kDicLayoutVersion;
  t.rows = rows;
  t.subsets = n;
  for (const cv::Point2d& p : result.positions) {
    t.x_px.push_back(p.x);
    t.y_px.push_back(p.y);
  }
  // Row by row, each appended to reserved (not yet touched) memory: the table's pages become
  // resident as the rows are released, so the results are held once while it fills.
  for (auto* column : {&t.u_px, &t.v_px}) column->reserve(rows * n);
  for (auto* column : {&t.zncc, &t.sigma_u_px, &t.sigma_v_px, &t.sigma_px})
    column->reserve(rows * n);
  for (auto* column : {&t.iterations, &t.status}) column->reserve(rows * n);
  // The warp gradients, when the correlation kept them (DicOptions::keep_warp_gradient).
  const bool gradients = !result.frames.empty() && !result.frames[0].dudx.empty();
  const std::array<std::vector<double>*, 4> warp = {&t.dudx_warp, &t.dudy_warp, &t.dvdx_warp,
                                                    &t.dvdy_warp};
  if (gradients)
    for (auto* column : warp) column->reserve(rows * n);
  // The number from the file names, else the index in the input sequence.
  const auto number = [&](int index) {
    return static_cast<double>(result.frame_numbers.empty() ? first_frame + index
                                                            : FrameLabel(result, index));
  };
  t.frame.push_back(first_frame);
  t.reference_frame.push_back(first_frame);
  t.frame_number.push_back(number(0));
  // The time stamps from the source (camera files), row by row.
  const auto time = [&](int index) { return result.time_s.at(static_cast<std::size_t>(index)); };
  if (!result.time_s.empty()) t.time_s.push_back(time(0));
  // Row 0: the first reference itself (NaN where the subset fails in it).
  for (std::size_t i = 0; i < n; ++i) {
    const SubsetStatus s =
        result.frames.empty() ? SubsetStatus::kConverged : result.frames[0].status[i];
    const bool fails = FailsInReference(s);
    t.u_px.push_back(fails ? std::nan("") : 0.0);
    t.v_px.push_back(fails ? std::nan("") : 0.0);
    t.status.push_back(static_cast<std::int32_t>(fails ? s : SubsetStatus::kConverged));
    if (gradients)
      for (auto* column : warp) column->push_back(fails ? std::nan("") : 0.0);
  }
  t.zncc.assign(n, 1.0f);
  t.sigma_u_px.assign(n, 0.0f);
  t.sigma_v_px.assign(n, 0.0f);
  t.sigma_px.assign(n, 0.0f);
  t.iterations.assign(n, 0);
  for (std::size_t r = 1; r < rows; ++r) {
    const FrameResult& f = result.frames[r - 1];
    t.frame.push_back(first_frame + f.frame);
    t.reference_frame.push_back(first_frame + f.reference_frame);
    t.frame_number.push_back(number(f.frame));
    if (!result.time_s.empty()) t.time_s.push_back(time(f.frame));
    t.u_px.insert(t.u_px.end(), f.u_px.begin(), f.u_px.end());
    t.v_px.insert(t.v_px.end(), f.v_px.begin(), f.v_px.end());
    t.zncc.insert(t.zncc.end(), f.zncc.begin(), f.zncc.end());
    t.sigma_u_px.insert(t.sigma_u_px.end(), f.sigma_u_px.begin(), f.sigma_u_px.end());
    t.sigma_v_px.insert(t.sigma_v_px.end(), f.sigma_v_px.begin(), f.sigma_v_px.end());
    t.sigma_px.insert(t.sigma_px.end(), f.sigma_px.begin(), f.sigma_px.end());
    t.iterations.insert(t.iterations.end(), f.iterations.begin(), f.iterations.end());
    if (gradients) {
      const std::array<const std::vector<double>*, 4> frame_warp = {&f.dudx, &f.dudy, &f.dvdx,
                                                                    &f.dvdy};
      for (std::size_t g = 0; g < warp.size(); ++g)
        warp[g]->insert(warp[g]->end(), frame_warp[g]->begin(), frame_warp[g]->end());
    }
    for (const SubsetStatus s : f.status) t.status.push_back(static_cast<std::int32_t>(s));
    if constexpr (!std::is_const_v<Result>) {
      result.frames[r - 1] = FrameResult{};
      // The rows are small blocks of the heap, the table a few large mappings: the pages the
      // released rows leave free go back to the system every kTrimRows rows as they free up.
      // Not after the last rows: the writing that follows reuses their pages (trimmed, each
      // would be faulted in again; a pair's table took 0.6 ms longer and its writing 1 ms).
      if (r % kTrimRows == 0) malloc_trim(0);
    }
  }
  t.status_codes = SubsetStatusCodes();
  t.text_attributes = {{"interpolation", ToString(options.icgn.interpolation)},
                       {"shape", ToString(options.icgn.shape)},
                       {"reference_update", ReferenceUpdateText(options.update)},
                       {"mode", ToString(options.mode)},
                       {"continuity_check", ContinuityCheckText(options.continuity)},
                       {"outlier_check", OutlierCheckText(options.outliers)},
                       {"summary", result.summary.BriefReport()}};
  t.number_attributes = {{"max_uncertainty_px", options.icgn.max_uncertainty_px},
                         {"subset_size_px", options.grid.subset_size},
                         {"step_px", options.grid.step},
                         {"valid_fraction", result.summary.valid_fraction},
                         {"mean_iterations", result.summary.mean_iterations},
                         {"reference_updates", result.summary.reference_updates},
                         {"discontinuous_results", double(result.summary.Discontinuous())},
                         {"outlier_results", double(result.summary.Outliers())}};
  if (!result.preprocess.empty()) t.text_attributes["preprocess"] = result.preprocess;
  for (const auto& [name, value] : result.text_attributes) t.text_attributes[name] = value;
  for (const auto& [name, value] : result.number_attributes) t.number_attributes[name] = value;
  return t;
}

}  // namespace

DicResultsTable MakeDicResultsTable(const DicResult& result, const DicOptions& options,
                                    int first_frame) {
  return MakeTable(result, options, first_frame);
}

DicResultsTable MakeDicResultsTable(DicResult&& result, const DicOptions& options,
                                    int first_frame) {
  return MakeTable(result, options, first_frame);
}

std::vector<std::string> DicCsvColumns(bool warp_gradient) {
  std::vector<std::string> columns = {"frame", "x_px",       "y_px",   "u_px",       "v_px",
                                      "zncc",  "iterations", "status", "sigma_u_px", "sigma_v_px"};
  if (warp_gradient)
    columns.insert(columns.end(), {"dudx_warp", "dudy_warp", "dvdx_warp", "dvdy_warp"});
  return columns;
}

void WriteDicResultsFile(const std::string& path, const DicResultsTable& t) {
  const std::string ext = ToLower(std::filesystem::path(path).extension().string());
  if (ext == ".csv") {
    // Row by row as they are formatted: the rows (about 10 strings per subset and frame) are
    // many times the results' own size and never all held at once. Row 0 (the reference) is left
    // out.
    const bool gradients = !t.dudx_warp.empty();
    const std::array<const std::vector<double>*, 4> warp = {&t.dudx_warp, &t.dudy_warp,
                                                            &t.dvdx_warp, &t.dvdy_warp};
    CsvRowWriter out(path, DicCsvColumns(gradients));
    std::vector<std::string> row;
    for (std::size_t r = 1; r < t.rows; ++r) {
      const std::string frame = std::to_string(std::llround(t.frame_number[r]));
      for (std::size_t i = 0; i < t.subsets; ++i) {
        const std::size_t k = r * t.subsets + i;
        row.assign({frame, Number(t.x_px[i]), Number(t.y_px[i]), Number(t.u_px[k]),
                    Number(t.v_px[k]), Number(t.zncc[k]), std::to_string(t.iterations[k]),
                    ToString(static_cast<SubsetStatus>(t.status[k])), Number(t.sigma_u_px[k]),
                    Number(t.sigma_v_px[k])});
        if (gradients)
          for (const auto* g : warp) row.push_back(Ratio((*g)[k]));
        out.Row(row);
      }
    }
    out.Commit();
    return;
  }
  if (ext != ".h5" && ext != ".hdf5") {
    throw Error(ErrorKind::kInvalidValue, "output", path, "a file ending in .csv or .h5");
  }
  // Other groups of an existing file stay.
  H5Writer out(path, /*owned_groups=*/{results_layout::kDicGroup});
  WriteDicResults(out, t);
  out.Commit();
}

void WriteDicResult(const std::string& path, DicResult* released, const DicOptions& options) {
  WriteDicResultsFile(path, MakeTable(*released, options, /*first_frame=*/-1));
}

}  // namespace impactdic
