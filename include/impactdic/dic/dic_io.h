// The correlator's results as the rows of the results files, and writing them (`correlate`).
//
//   DicResult r = CorrelateFrames(*OpenFrameSource("frames/"), options);  // dic/correlate_frames.h
//   WriteDicResult("out.h5", &r, options);  // or .csv; r.frames released
//   WriteDicResultsFile("out.csv", table);  // a DicResultsTable (`correlate`)
#ifndef IMPACTDIC_DIC_DIC_IO_H_
#define IMPACTDIC_DIC_DIC_IO_H_

#include <string>
#include <vector>

#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/dic_results.h"

namespace impactdic {

// Whether a subset's displacement is used downstream (kinematics, momentum, figures): only a
// converged subset (the status code results_layout::kValidStatusCode in files).
bool IsValidStatus(SubsetStatus status);

// Whether a status of the first deformed frame is the reference's own fault (masked, featureless,
// low contrast, saturated): such a subset has no valid displacement in the reference row either.
bool FailsInReference(SubsetStatus status);

// The result as the rows of the results files (io/dic_results.h, io/results_layout.h): row 0 the
// first reference (zero displacement, NaN where FailsInReference), then one row per deformed
// frame; frame indices offset by `first_frame` (the first reference's index in the camera
// sequence; -1: unknown, the indices are those of the images correlated and no first_frame
// attribute is written); the options and the summary as attributes.
DicResultsTable MakeDicResultsTable(const DicResult& result, const DicOptions& options,
                                    int first_frame);
// The same from a result that is not needed afterwards: each frame's arrays are released once
// copied, so the subsets x frames results are in memory once (plus one frame), not twice.
DicResultsTable MakeDicResultsTable(DicResult&& result, const DicOptions& options, int first_frame);

// Writes the table (MakeDicResultsTable) by extension:
// .csv: columns frame,x_px,y_px,u_px,v_px,zncc,iterations,status,sigma_u_px,sigma_v_px (one row
//       per frame and subset;
//       frame = the deformed image's frame number from its file name (frame_0012.png -> 12) when
//       the names are one numbered series, else its 1-based index; x,y = subset centre in the
//       first reference,
//       u,v = accumulated displacement [px], x right, y down; status by name; sigma_u,v = their
//       estimated standard deviations against the frame's reference [px]; NaN as "nan"),
//       then, only when the correlation kept them (DicOptions::keep_warp_gradient), the columns
//       dudx_warp,dudy_warp,dvdx_warp,dvdy_warp: the displacement gradient of the subset warp
//       since the first reference (FrameResult::dudx ...; 9 significant digits).
// .h5:  the /dic group of the results layout (io/results_layout.h, written by
//       WriteDicResults): one row per image, the
//       reference first; /dic/frame_number as the CSV's frame column; other groups of an existing
//       file are kept.
// The .csv is written row by row as formatted; the .h5 atomically (io/hdf5_store.h).
void WriteDicResultsFile(const std::string& path, const DicResultsTable& table);
// The same for MakeDicResultsTable(result, options, /*first_frame=*/-1): each frame's arrays are
// released once in the table, so the results are held once; the positions, summary and
// attributes stay in *result.
void WriteDicResult(const std::string& path, DicResult* result, const DicOptions& options);
// The columns of WriteDicResult's CSV; `warp_gradient`: with the warp-gradient columns (they
// come last, so every CSV begins with DicCsvColumns()).
std::vector<std::string> DicCsvColumns(bool warp_gradient = false);

}  // namespace impactdic

#endif  // IMPACTDIC_DIC_DIC_IO_H_
