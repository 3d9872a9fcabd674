#include "impactdic/strain/strain_results.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"

namespace impactdic {
namespace {
namespace L = results_layout;

StrainResult SmallResult() {
  DisplacementGradient g;
  g.frames = 4;
  g.subsets = 3;
  for (std::size_t j = 0; j < 12; ++j) {
    const double k = static_cast<double>(j / 3);
    g.dudx.push_back(0.001 * k);
    g.dudy.push_back(0.002 * k);
    g.dvdx.push_back(0.0);
    g.dvdy.push_back(-0.01 * k);
  }
  g.dvdy[5] = kNaN;
  StrainResult r;
  r.options.enabled = true;
  r.options.window = 7;
  r.options.compaction_threshold = 0.02;
  r.gradient = g;
  r.field = ComputeStrain(g, /*fps=*/1000);
  r.dry_density_kg_m3 = 1550;
  r.density_kg_m3 = DensityField(r.field, r.dry_density_kg_m3);
  r.shear_band.assign(12, 0);
  r.shear_band[7] = 1;
  r.zone_end = {3, 2, 12.5, 4.25};
  r.te_known = false;
  r.te_note = "t_e is not known: the momentum stage did not run";
  r.depth_from = "grid top row";
  r.surface_y_px = 40;
  return r;
}

StrainResult RoundTrip(const StrainResult& r) {
  H5Writer out("strain.h5", H5Writer::Mode::kCreate, "", H5Writer::Backing::kMemory);
  WriteStrainResults(out, r);
  const std::vector<char> image = out.CommitToMemory();
  return ReadStrainResults(H5Reader("strain.h5", image), "strain.h5");
}

void ExpectSame(const std::vector<double>& a, const std::vector<double>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i])) {
      EXPECT_TRUE(std::isnan(b[i])) << i;
    } else {
      EXPECT_EQ(a[i], b[i]) << i;
    }
  }
}

TEST(StrainResults, WriteThenReadGivesTheSameFieldsAndAttributes) {
  const StrainResult r = SmallResult();
  const StrainResult b = RoundTrip(r);
  EXPECT_EQ(b.field.frames, 4u);
  EXPECT_EQ(b.field.subsets, 3u);
  ExpectSame(b.gradient.dvdy, r.gradient.dvdy);
  ExpectSame(b.field.gxx, r.field.gxx);
  ExpectSame(b.field.eps_v, r.field.eps_v);
  ExpectSame(b.field.theta_1_rad, r.field.theta_1_rad);
  ExpectSame(b.field.gamma_max_rate, r.field.gamma_max_rate);
  ExpectSame(b.density_kg_m3, r.density_kg_m3);
  EXPECT_EQ(b.shear_band, r.shear_band);
  EXPECT_EQ(b.options.gradient, StrainGradient::kFit);
  EXPECT_EQ(b.options.window, 7);
  EXPECT_EQ(b.options.compaction_threshold, 0.02);
  EXPECT_FALSE(b.te_known);
  EXPECT_TRUE(std::isnan(b.zone_te.depth_mm));
  EXPECT_EQ(b.te_note, r.te_note);
  EXPECT_EQ(b.zone_end.frame, 3u);
  EXPECT_EQ(b.zone_end.depth_mm, 4.25);
  EXPECT_EQ(b.zone_end.area_mm2, 12.5);
  EXPECT_EQ(b.depth_from, "grid top row");
  EXPECT_EQ(b.dry_density_kg_m3, 1550);
}

TEST(StrainResults, UnitsAndConventionsAreAttributes) {
  StrainResult r = SmallResult();
  r.options.gradient = StrainGradient::kWarp;
  r.te_known = true;
  r.zone_te = {2, 1, 6.25, 2.0};
  H5Writer out("strain.h5", H5Writer::Mode::kCreate, "", H5Writer::Backing::kMemory);
  WriteStrainResults(out, r);
  const std::vector<char> image = out.CommitToMemory();
  const H5Reader in("strain.h5", image);
  EXPECT_EQ(in.ReadStringAttribute(L::kStrainGroup, L::kStrainGradientAttr), "warp");
  const std::string convention = in.ReadStringAttribute(L::kStrainGroup, L::kStrainConventionAttr);
  EXPECT_NE(convention.find("COMPRESSION positive"), std::string::npos) << convention;
  EXPECT_NE(convention.find("y DOWN"), std::string::npos) << convention;
  EXPECT_EQ(in.ReadStringAttribute(L::kStrainEpsVRate, "units"), "1/s");
  EXPECT_EQ(in.ReadStringAttribute(L::kStrainDensity, "units"), "kg/m^3");
  EXPECT_EQ(in.ReadStringAttribute(L::kStrainTheta1, "units"), "rad");
  EXPECT_EQ(in.ReadNumberAttribute(L::kStrainGroup, "compacted_depth_te_mm"), 2.0);
  EXPECT_EQ(in.ReadNumberAttribute(L::kStrainGroup, "compacted_te_frame"), 2.0);
  const StrainResult b = ReadStrainResults(in, "strain.h5");
  EXPECT_TRUE(b.te_known);
  EXPECT_EQ(b.zone_te.frame, 2u);
  EXPECT_EQ(b.options.gradient, StrainGradient::kWarp);
}

TEST(StrainResults, ReadingAFileWithoutStrainNamesTheGroup) {
  H5Writer out("none.h5", H5Writer::Mode::kCreate, "", H5Writer::Backing::kMemory);
  out.CreateGroup("/dic");
  const std::vector<char> image = out.CommitToMemory();
  try {
    ReadStrainResults(H5Reader("none.h5", image), "none.h5");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/strain"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("strain.enabled"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace impactdic
