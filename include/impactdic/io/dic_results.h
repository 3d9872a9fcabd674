// The DIC results of a file (the /dic group of results.h5 and of `impactdic correlate -o X.h5`):
// one table, one writer, one reader. The layout (names, shapes, row 0 = the first reference) is in
// io/results_layout.h; the dic module fills the table from its result (dic/dic_io.h
// MakeDicResultsTable), the momentum module reads it back (ReadCorrelationSeries).
//
//   H5Writer out("run/results.h5");
//   WriteDicResults(out, MakeDicResultsTable(result, options, /*first_frame=*/0));
//   out.Commit();
//   const DicResultsTable t = ReadDicResults(H5Reader("run/results.h5"), "run/results.h5");
#ifndef IMPACTDIC_IO_DIC_RESULTS_H_
#define IMPACTDIC_IO_DIC_RESULTS_H_

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"

namespace impactdic {

// The arrays of the /dic group, row-major [rows x subsets]; row 0 is the first reference.
struct DicResultsTable {
  int layout_version = 0;  // As read (1 = written before versions existed); written: the current.
  std::size_t rows = 0, subsets = 0;
  std::vector<double> x_px, y_px;  // Subset centres in the first reference [subsets].
  std::vector<double> u_px, v_px;  // Accumulated displacement [rows x subsets], NaN = failed.
  // [rows x subsets]; empty = not in the file (read: then every finite displacement is valid).
  std::vector<std::int32_t> status, iterations;
  std::vector<float> zncc, sigma_u_px, sigma_v_px, sigma_px;
  // [rows x subsets], only when the correlation kept them (DicOptions::keep_warp_gradient);
  // empty = not in the file: the displacement gradient of the subset warp since the first
  // reference (du/dX, du/dY, dv/dX, dv/dY; 0 in row 0 where valid, NaN = failed).
  std::vector<double> dudx_warp, dudy_warp, dvdx_warp, dvdy_warp;
  // [rows]: image index in the input sequence, frame number (file name), reference image index.
  // Empty = not in the file.
  std::vector<std::int32_t> frame, reference_frame;
  std::vector<double> frame_number;
  std::vector<double> time_s;  // [rows]: time stamp from the source [s]; empty = none.
  long first_frame = -1;       // Index of row 0 in the input sequence; -1 = not in the file.
  std::string status_codes;    // "0=converged, 1=..." (attribute of /dic/status); "" = none.
  // Further attributes of /dic (the options, the correlation's summary).
  std::map<std::string, double> number_attributes;
  std::map<std::string, std::string> text_attributes;

  // true where sample k (row-major) is valid: its status is results_layout::kValidStatusCode
  // (or no status is stored) and its displacement is finite.
  bool IsValid(std::size_t k) const;
  // Error(kInvalidValue) naming the field whose size does not match rows x subsets.
  void Check() const;
};

// Writes the table as the /dic group (current layout version; replaces an existing /dic).
void WriteDicResults(H5Writer& out, const DicResultsTable& table);

// Reads the /dic group in any layout version (results_layout.h): the table in the current layout
// (a correlate file of version 1 gets its reference row prepended). Error kFileFormat naming
// `file` and the dataset when it is missing or its shape or frame indices are inconsistent.
// kDisplacements reads the grid, u_px, v_px and the per-row indices only, not the per-sample
// status, quality and warp gradients (status, iterations, zncc, sigmas, *_warp stay empty): what
// a reader of the motion
// needs, without four more arrays of rows x subsets in memory (render's velocity field).
enum class DicFields { kAll, kDisplacements };
DicResultsTable ReadDicResults(const H5Reader& in, const std::string& file,
                               DicFields fields = DicFields::kAll);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_DIC_RESULTS_H_
