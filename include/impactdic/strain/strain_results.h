// The strain results of a run (the /strain group of results.h5, io/results_layout.h; definitions
// in strain/strain.h, docs/strain.md): one struct, one writer, one reader.
//
//   StrainResult r = ...;            // the pipeline's strain stage fills it
//   H5Writer out("run/results.h5");
//   WriteStrainResults(out, r);
//   out.Commit();
//   StrainResult back = ReadStrainResults(H5Reader("run/results.h5"), "run/results.h5");
#ifndef IMPACTDIC_STRAIN_STRAIN_RESULTS_H_
#define IMPACTDIC_STRAIN_STRAIN_RESULTS_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/strain/strain.h"

namespace impactdic {

struct StrainResult {
  StrainOptions options;  // As used (gradient, window, thresholds).
  DisplacementGradient gradient;
  StrainField field;
  double dry_density_kg_m3 = kNaN;       // rho_d (test.density_kg_m3).
  std::vector<double> density_kg_m3;     // DensityField, [frames x subsets].
  std::vector<std::uint8_t> shear_band;  // ShearBands, [frames x subsets].
  // The compacted zone at t_e (te_frame; zone_te's figures NaN with te_note saying why when t_e
  // is not known) and at the last frame; depths from depth_from ("momentum.surface_y_px" or "grid
  // top row") at surface_y_px [px].
  CompactedZone zone_te{0, 0, kNaN, kNaN}, zone_end;
  bool te_known = false;
  std::string te_note;
  std::string depth_from;
  double surface_y_px = kNaN;
};

// One [frames x subsets] double dataset of /strain (its path in io/results_layout.h, units,
// description) bound to a result's values.
struct StrainMeasure {
  const char* path;
  const char* units;
  const char* description;
  const std::vector<double>* values;
  std::string Name() const;  // The path's last part ("eps_v"): the strain.csv column.
};
// Every double dataset of /strain, in the order written (the gradient, the strains, the rates,
// the density); the uint8 shear_band is apart.
std::vector<StrainMeasure> StrainMeasures(const StrainResult& result);

// The "convention" attribute of /strain: the sign conventions in words.
const char* StrainConventionText();

// Writes /strain (replacing an existing group): every dataset of io/results_layout.h with units
// and descriptions, the attributes gradient, convention, window, compaction_threshold,
// shear_band_threshold, dry_density_kg_m3, the compacted zone's (compacted_area_te_mm2, ...,
// compacted_te_note, compacted_te_frame, compacted_end_frame), depth_from and surface_y_px.
void WriteStrainResults(H5Writer& out, const StrainResult& result);

// Reads /strain back. Error kFileFormat naming `file` and the dataset or attribute when missing or
// of the wrong shape.
StrainResult ReadStrainResults(const H5Reader& in, const std::string& file);

}  // namespace impactdic

#endif  // IMPACTDIC_STRAIN_STRAIN_RESULTS_H_
