#include "impactdic/io/dic_results.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "impactdic/core/error.h"
#include "impactdic/io/results_layout.h"

namespace impactdic {
namespace L = results_layout;
namespace {

// Error kInvalidValue naming `field` unless `values` is empty or holds `expected` entries.
template <typename T>
void CheckSize(const std::vector<T>& values, std::size_t expected, const char* field) {
  if (values.empty() || values.size() == expected) return;
  throw Error(ErrorKind::kInvalidValue, field, fmt::format("{} entries", values.size()),
              fmt::format("{} (rows x subsets, or rows)", expected));
}

std::string RowsText(const Dims& d) {
  std::string t = "[";
  for (std::size_t i = 0; i < d.size(); ++i) t += (i ? " x " : "") + std::to_string(d[i]);
  return t + "]";
}

template <typename T>
void PrependRow(std::vector<T>* values, std::size_t n, T value) {
  if (!values->empty()) values->insert(values->begin(), n, value);
}

// Version 1 of `impactdic correlate` held the deformed images only (/dic/frame 1-based): the
// reference row is prepended so that row k is image k.
void PrependReferenceRow(DicResultsTable* t) {
  const std::size_t n = t->subsets;
  PrependRow(&t->u_px, n, 0.0);
  PrependRow(&t->v_px, n, 0.0);
  PrependRow(&t->status, n, std::int32_t{L::kValidStatusCode});
  PrependRow(&t->iterations, n, std::int32_t{0});
  PrependRow(&t->zncc, n, 1.0f);
  PrependRow(&t->sigma_u_px, n, 0.0f);
  PrependRow(&t->sigma_v_px, n, 0.0f);
  PrependRow(&t->sigma_px, n, 0.0f);
  for (auto* g : {&t->dudx_warp, &t->dudy_warp, &t->dvdx_warp, &t->dvdy_warp})
    PrependRow(g, n, 0.0);
  PrependRow(&t->frame, 1, std::int32_t{0});
  PrependRow(&t->reference_frame, 1, std::int32_t{0});
  PrependRow(&t->frame_number, 1, std::nan(""));
  ++t->rows;
}

// /dic/frame of a version-1 file: consecutive image indices, one per row, starting at 0
// (reference row included, as `run` wrote) or 1 (the deformed images, as `correlate` wrote).
void CheckVersion1Frames(const DicResultsTable& t, const std::string& file) {
  const std::vector<std::int32_t>& index = t.frame;
  for (std::size_t k = 0; k < index.size(); ++k) {
    if (index.size() != t.rows || index[k] != index[0] + static_cast<std::int32_t>(k)) {
      throw Error(ErrorKind::kFileFormat, L::kDicFrame,
                  fmt::format("{} indices starting {}, not consecutive or not one per row",
                              index.size(), index.empty() ? -1 : index[0]),
                  "consecutive image indices, one per row of /dic/u_px")
          .WithFile(file);
    }
  }
  if (!index.empty() && index[0] != 0 && index[0] != 1) {
    throw Error(ErrorKind::kFileFormat, L::kDicFrame, fmt::format("first index {}", index[0]),
                "0 (reference row included) or 1 (first deformed image)")
        .WithFile(file);
  }
}

// Reads the optional dataset `path` into *values when the file has it; Error naming it when its
// size is not `expected`.
template <typename T, typename Read>
void ReadOptional(const H5Reader& in, const std::string& file, const char* path,
                  std::size_t expected, Read read, std::vector<T>* values) {
  if (!in.Exists(path)) return;
  *values = read(path);
  if (values->size() == expected) return;
  throw Error(ErrorKind::kFileFormat, path, fmt::format("{} entries", values->size()),
              fmt::format("one per row and subset, or per row ({})", expected))
      .WithFile(file);
}

void ReadGrid(const H5Reader& in, const std::string& file, DicResultsTable* t) {
  for (const char* path : {L::kDicX, L::kDicY, L::kDicU, L::kDicV}) {
    if (!in.Exists(path)) {
      throw Error(ErrorKind::kFileFormat, path, "missing",
                  "the correlation results (run `impactdic correlate` or `impactdic run` first)")
          .WithFile(file);
    }
  }
  Dims du, dv;
  t->u_px = in.ReadDouble(L::kDicU, &du);
  t->v_px = in.ReadDouble(L::kDicV, &dv);
  t->x_px = in.ReadDouble(L::kDicX);
  t->y_px = in.ReadDouble(L::kDicY);
  if (du.size() < 2 || du != dv || du[0] == 0) {
    throw Error(ErrorKind::kFileFormat, "/dic/u_px, /dic/v_px",
                fmt::format("datasets of shape {} and {}", RowsText(du), RowsText(dv)),
                "equal [frames x subsets] (or [frames x rows x cols]) datasets")
        .WithFile(file);
  }
  t->rows = du[0];
  t->subsets = t->u_px.size() / t->rows;
  // Positions per subset, or per frame and subset (then the first row).
  if (t->subsets == 0 || t->x_px.size() < t->subsets || t->y_px.size() != t->x_px.size() ||
      t->x_px.size() % t->subsets != 0) {
    throw Error(
        ErrorKind::kFileFormat, "/dic/x_px, /dic/y_px",
        fmt::format("{} / {} entries", t->x_px.size(), t->y_px.size()),
        fmt::format("one position per subset ({}), or one per frame and subset", t->subsets))
        .WithFile(file);
  }
  t->x_px.resize(t->subsets);
  t->y_px.resize(t->subsets);
}

// The four warp-gradient datasets, each only when the table has it.
void WriteWarpGradient(H5Writer& out, const DicResultsTable& t) {
  const Dims dims{t.rows, t.subsets};
  const struct {
    const char* path;
    const std::vector<double>& values;
    const char* what;
  } gradients[] = {{L::kDicDudxWarp, t.dudx_warp, "du/dX"},
                   {L::kDicDudyWarp, t.dudy_warp, "du/dY"},
                   {L::kDicDvdxWarp, t.dvdx_warp, "dv/dX"},
                   {L::kDicDvdyWarp, t.dvdy_warp, "dv/dY"}};
  for (const auto& g : gradients) {
    if (g.values.empty()) continue;
    out.Write(g.path, g.values, dims, "1",
              std::string(g.what) +
                  " of the subset warp since the first reference (row 0), in first-reference "
                  "coordinates (x right, y down), composed across reference updates; NaN = failed");
  }
}

}  // namespace

bool DicResultsTable::IsValid(std::size_t k) const {
  if (!status.empty()) return status[k] == L::kValidStatusCode;
  return std::isfinite(u_px[k]) && std::isfinite(v_px[k]);
}

void DicResultsTable::Check() const {
  const std::size_t n = rows * subsets;
  CheckValue(x_px.size() == subsets && y_px.size() == subsets, "x_px, y_px",
             fmt::format("{} / {} entries", x_px.size(), y_px.size()),
             fmt::format("one per subset ({})", subsets));
  CheckValue(u_px.size() == n && v_px.size() == n, "u_px, v_px",
             fmt::format("{} / {} entries", u_px.size(), v_px.size()),
             fmt::format("rows x subsets ({})", n));
  CheckSize(status, n, "status");
  CheckSize(iterations, n, "iterations");
  CheckSize(zncc, n, "zncc");
  CheckSize(sigma_u_px, n, "sigma_u_px");
  CheckSize(sigma_v_px, n, "sigma_v_px");
  CheckSize(sigma_px, n, "sigma_px");
  CheckSize(dudx_warp, n, "dudx_warp");
  CheckSize(dudy_warp, n, "dudy_warp");
  CheckSize(dvdx_warp, n, "dvdx_warp");
  CheckSize(dvdy_warp, n, "dvdy_warp");
  CheckSize(frame, rows, "frame");
  CheckSize(reference_frame, rows, "reference_frame");
  CheckSize(frame_number, rows, "frame_number");
  CheckSize(time_s, rows, "time_s");
}

void WriteDicResults(H5Writer& out, const DicResultsTable& t) {
  t.Check();
  out.Remove(L::kDicGroup);
  const Dims dims{t.rows, t.subsets}, rows{t.rows};
  out.Write(L::kDicX, t.x_px, "px", "subset centre x in the first reference (x right)");
  out.Write(L::kDicY, t.y_px, "px", "subset centre y in the first reference (y down)");
  out.Write(L::kDicU, t.u_px, dims, "px",
            "accumulated displacement x (right) since the first reference (row 0); NaN = failed");
  out.Write(L::kDicV, t.v_px, dims, "px",
            "accumulated displacement y (down) since the first reference (row 0); NaN = failed");
  if (!t.zncc.empty())
    out.Write(L::kDicZncc, t.zncc, dims, "1", "zero-normalised cross-correlation of the subset");
  if (!t.status.empty()) {
    out.Write(L::kDicStatus, t.status, dims, "1",
              "subset status code (attribute codes); 0 = converged, the only valid status");
    if (!t.status_codes.empty())
      out.SetAttribute(L::kDicStatus, L::kStatusCodesAttr, t.status_codes);
  }
  if (!t.iterations.empty())
    out.Write(L::kDicIterations, t.iterations, dims, "1", "IC-GN iterations");
  const char* sigma_note = "(least-squares covariance; 0 in row 0, NaN = failed)";
  if (!t.sigma_u_px.empty()) {
    out.Write(L::kDicSigmaU, t.sigma_u_px, dims, "px",
              std::string("estimated standard deviation of u against the frame's reference ") +
                  sigma_note);
  }
  if (!t.sigma_v_px.empty()) {
    out.Write(L::kDicSigmaV, t.sigma_v_px, dims, "px",
              std::string("estimated standard deviation of v against the frame's reference ") +
                  sigma_note);
  }
  if (!t.sigma_px.empty())
    out.Write(L::kDicSigma, t.sigma_px, dims, "px", "the larger of sigma_u_px and sigma_v_px");
  WriteWarpGradient(out, t);
  if (!t.frame.empty()) {
    out.Write(L::kDicFrame, t.frame, rows, "1",
              "index of the row's image in the input sequence (0 = its first image)");
  }
  if (!t.frame_number.empty()) {
    out.Write(L::kDicFrameNumber, t.frame_number, "1",
              "frame number of the row's image from its file name (its index when the names are "
              "not one numbered series)");
  }
  if (!t.time_s.empty()) {
    out.Write(L::kDicTimeS, t.time_s, "s",
              "time stamp of the row's image from its source (a camera file's, relative to the "
              "trigger)");
  }
  if (!t.reference_frame.empty()) {
    out.Write(L::kDicReferenceFrame, t.reference_frame, rows, "1",
              "index in the input sequence of the reference image the row was correlated against");
  }
  out.SetAttribute(L::kDicGroup, L::kLayoutVersionAttr, double{L::kDicLayoutVersion});
  if (t.first_frame >= 0)
    out.SetAttribute(L::kDicGroup, L::kFirstFrameAttr, static_cast<double>(t.first_frame));
  for (const auto& [name, value] : t.number_attributes) out.SetAttribute(L::kDicGroup, name, value);
  for (const auto& [name, value] : t.text_attributes) out.SetAttribute(L::kDicGroup, name, value);
}

DicResultsTable ReadDicResults(const H5Reader& in, const std::string& file, DicFields fields) {
  DicResultsTable t;
  ReadGrid(in, file, &t);
  t.layout_version = in.HasAttribute(L::kDicGroup, L::kLayoutVersionAttr)
                         ? static_cast<int>(std::lround(
                               in.ReadNumberAttribute(L::kDicGroup, L::kLayoutVersionAttr)))
                         : 1;
  if (t.layout_version < 1 || t.layout_version > L::kDicLayoutVersion) {
    throw Error(ErrorKind::kFileFormat,
                std::string("attribute ") + L::kLayoutVersionAttr + " of " + L::kDicGroup,
                std::to_string(t.layout_version),
                fmt::format("1..{} (a file written by a newer impactdic?)", L::kDicLayoutVersion))
        .WithFile(file);
  }
  const std::size_t n = t.rows * t.subsets;
  const auto ints = [&in](const std::string& p) { return in.ReadInt(p); };
  const auto floats = [&in](const std::string& p) { return in.ReadFloat(p); };
  const auto doubles = [&in](const std::string& p) { return in.ReadDouble(p); };
  if (fields == DicFields::kAll) {
    ReadOptional(in, file, L::kDicStatus, n, ints, &t.status);
    ReadOptional(in, file, L::kDicIterations, n, ints, &t.iterations);
    ReadOptional(in, file, L::kDicZncc, n, floats, &t.zncc);
    ReadOptional(in, file, L::kDicSigmaU, n, floats, &t.sigma_u_px);
    ReadOptional(in, file, L::kDicSigmaV, n, floats, &t.sigma_v_px);
    ReadOptional(in, file, L::kDicSigma, n, floats, &t.sigma_px);
    ReadOptional(in, file, L::kDicDudxWarp, n, doubles, &t.dudx_warp);
    ReadOptional(in, file, L::kDicDudyWarp, n, doubles, &t.dudy_warp);
    ReadOptional(in, file, L::kDicDvdxWarp, n, doubles, &t.dvdx_warp);
    ReadOptional(in, file, L::kDicDvdyWarp, n, doubles, &t.dvdy_warp);
  }
  if (t.sigma_u_px.empty() != t.sigma_v_px.empty()) {
    t.sigma_u_px.clear();  // Only both together are of use.
    t.sigma_v_px.clear();
  }
  const std::array<std::vector<double>*, 4> warp = {&t.dudx_warp, &t.dudy_warp, &t.dvdx_warp,
                                                    &t.dvdy_warp};
  if (std::any_of(warp.begin(), warp.end(), [](const auto* g) { return g->empty(); }))
    for (auto* g : warp) g->clear();  // Only the four together are a gradient.
  ReadOptional(in, file, L::kDicFrame, t.rows, ints, &t.frame);
  ReadOptional(in, file, L::kDicReferenceFrame, t.rows, ints, &t.reference_frame);
  ReadOptional(in, file, L::kDicFrameNumber, t.rows, doubles, &t.frame_number);
  ReadOptional(in, file, L::kDicTimeS, t.rows, doubles, &t.time_s);
  if (in.HasAttribute(L::kDicStatus, L::kStatusCodesAttr))
    t.status_codes = in.ReadStringAttribute(L::kDicStatus, L::kStatusCodesAttr);
  else if (in.HasAttribute(L::kDicStatus, "status_names"))  // Version 1 of `run`.
    t.status_codes = in.ReadStringAttribute(L::kDicStatus, "status_names");
  if (in.HasAttribute(L::kDicGroup, L::kFirstFrameAttr))
    t.first_frame = std::lround(in.ReadNumberAttribute(L::kDicGroup, L::kFirstFrameAttr));
  if (t.layout_version == 1) {
    CheckVersion1Frames(t, file);
    if (!t.frame.empty() && t.frame[0] == 1) PrependReferenceRow(&t);
    // Version 1 of `run` had no /dic/frame: its rows are the frames from first_frame on.
    if (t.frame.empty() && in.Exists(L::kTimeFrameIndex)) {
      const std::vector<double> index = in.ReadDouble(L::kTimeFrameIndex);
      if (index.size() == t.rows)
        for (double i : index) t.frame.push_back(static_cast<std::int32_t>(std::lround(i)));
    }
  }
  try {
    t.Check();
  } catch (Error& e) {
    e.WithFile(file);
    throw;
  }
  return t;
}

}  // namespace impactdic
