#include "impactdic/dic/options.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"
#include "impactdic/dic/reference_update.h"

namespace impactdic {
namespace {

const char* const kStatusNames[kSubsetStatusCount] = {
    "converged", "max_iterations", "low_correlation", "singular_hessian", "out_of_image",
    "masked",    "low_contrast",   "saturated",       "not_found",        "lost",
    "uncertain", "discontinuous",  "outlier"};

std::string Num(double v) { return std::to_string(v); }

}  // namespace

const char* ToString(ShapeFunction shape) { return kShapeFunctionNames.Name(shape); }

ShapeFunction ShapeFunctionFromString(const std::string& name) {
  return kShapeFunctionNames.Parse(name, "shape function");
}

std::string ReferenceUpdateText(const UpdateOptions& update) { return update.policy; }

const char* ToString(SequenceMode mode) { return kSequenceModeNames.Name(mode); }

SequenceMode SequenceModeFromString(const std::string& text, const std::string& where) {
  return kSequenceModeNames.Parse(text, where);
}

double MaxUncertaintyFromString(const std::string& text, const std::string& where) {
  if (text == "none") return std::numeric_limits<double>::infinity();
  const std::optional<double> value = ParseNumber(text);
  CheckValue(value && *value >= 0 && !std::isnan(*value), where, text,
             "an uncertainty limit >= 0 [px] (0 or none: no limit)");
  return *value;
}

std::string MaxUncertaintyText(double max_uncertainty_px) {
  return max_uncertainty_px > 0 && std::isfinite(max_uncertainty_px)
             ? fmt::format("{}", max_uncertainty_px)
             : "none";
}

std::string SubsetStatusCodes() {
  std::string codes;
  for (int s = 0; s < kSubsetStatusCount; ++s)
    codes += fmt::format("{}{}={}", s ? "," : "", s, ToString(static_cast<SubsetStatus>(s)));
  return codes;
}

const char* ToString(SubsetStatus status) {
  const int i = static_cast<int>(status);
  return i >= 0 && i < kSubsetStatusCount ? kStatusNames[i] : "?";
}

SubsetStatus SubsetStatusFromString(const std::string& name) {
  for (int i = 0; i < kSubsetStatusCount; ++i) {
    if (name == kStatusNames[i]) return static_cast<SubsetStatus>(i);
  }
  std::string all;
  for (int i = 0; i < kSubsetStatusCount; ++i) all += std::string(i ? ", " : "") + kStatusNames[i];
  throw Error(ErrorKind::kInvalidValue, "subset status", name, "one of " + all);
}

void GridOptions::Check() const {
  CheckValue(kSubsetSizeRange.Contains(subset_size) && subset_size % 2 == 1, "dic.grid.subset_size",
             std::to_string(subset_size), "an odd integer in " + kSubsetSizeRange.Text());
  CheckValue(kGridStepRange.Contains(step), "dic.grid.step", std::to_string(step),
             "an integer in " + kGridStepRange.Text());
  CheckValue(roi.width >= 0 && roi.height >= 0 && roi.x >= 0 && roi.y >= 0, "dic.grid.roi",
             "x=" + std::to_string(roi.x) + " y=" + std::to_string(roi.y) +
                 " w=" + std::to_string(roi.width) + " h=" + std::to_string(roi.height),
             "a rectangle with non-negative origin and size (empty = whole image)");
  CheckValue(mask.empty() || (mask.type() == CV_8UC1), "dic.grid.mask", "a non-8-bit mask",
             "an 8-bit one-channel mask (0 = excluded)");
}

void InitialGuessOptions::Check() const {
  CheckValue(kSearchRadiusRange.Contains(search_radius_px), "dic.init.search_radius_px",
             std::to_string(search_radius_px), "an integer in " + kSearchRadiusRange.Text());
  CheckValue(seed_spacing >= 1, "dic.init.seed_spacing", std::to_string(seed_spacing), ">= 1");
  CheckValue(min_search_zncc > -1 && min_search_zncc < 1, "dic.init.min_search_zncc",
             Num(min_search_zncc), "in (-1, 1)");
}

void IcgnOptions::Check() const {
  CheckValue(kConvergenceRange.Contains(convergence_px), "dic.icgn.convergence_px",
             Num(convergence_px), "in " + kConvergenceRange.Text());
  CheckValue(kConvergenceSigmaFractionRange.Contains(convergence_sigma_fraction),
             "dic.icgn.convergence_sigma_fraction", Num(convergence_sigma_fraction),
             "in " + kConvergenceSigmaFractionRange.Text());
  CheckValue(kMaxIterationsRange.Contains(max_iterations), "dic.icgn.max_iterations",
             std::to_string(max_iterations), "in " + kMaxIterationsRange.Text());
  CheckValue(kMinZnccRange.Contains(min_zncc), "dic.icgn.min_zncc", Num(min_zncc),
             "in " + kMinZnccRange.Text());
  CheckValue(kMinContrastRange.Contains(min_contrast), "dic.icgn.min_contrast", Num(min_contrast),
             "in " + kMinContrastRange.Text());
  CheckValue(kMaxPredictedUncertaintyRange.Contains(max_predicted_uncertainty_px),
             "dic.icgn.max_predicted_uncertainty_px", Num(max_predicted_uncertainty_px),
             "in " + kMaxPredictedUncertaintyRange.Text());
  CheckValue(max_uncertainty_px >= 0, "dic.icgn.max_uncertainty_px", Num(max_uncertainty_px),
             "> 0 px");
  CheckValue(kMaxSaturatedFractionRange.Contains(max_saturated_fraction),
             "dic.icgn.max_saturated_fraction", Num(max_saturated_fraction),
             "in " + kMaxSaturatedFractionRange.Text());
}

void UpdateOptions::Check() const {
  try {
    ReferenceUpdatePolicyFromString(policy, *this);
  } catch (const Error&) {
    throw Error(ErrorKind::kInvalidValue, "dic.update.policy", policy,
                ReferenceUpdatePolicyUsage());
  }
  CheckValue(kAutoMinZnccRange.Contains(auto_min_zncc), "dic.update.auto_min_zncc",
             Num(auto_min_zncc), "in " + kAutoMinZnccRange.Text());
  CheckValue(kAutoRescueDecorrelationRange.Contains(auto_rescue_decorrelation),
             "dic.update.auto_rescue_decorrelation", Num(auto_rescue_decorrelation),
             "in " + kAutoRescueDecorrelationRange.Text());
}

void OutlierCheckOptions::Check() const {
  CheckValue(kOutlierThresholdRange.Contains(threshold), "dic.outliers.threshold", Num(threshold),
             "in " + kOutlierThresholdRange.Text());
  CheckValue(kOutlierNoiseRange.Contains(noise_px), "dic.outliers.noise_px", Num(noise_px),
             "in " + kOutlierNoiseRange.Text());
  CheckValue(kOutlierSigmaFactorRange.Contains(sigma_factor), "dic.outliers.sigma_factor",
             Num(sigma_factor), "in " + kOutlierSigmaFactorRange.Text());
  CheckValue(kOutlierNeighboursRange.Contains(min_neighbours), "dic.outliers.min_neighbours",
             std::to_string(min_neighbours), "in " + kOutlierNeighboursRange.Text());
}

std::string OutlierCheckText(const OutlierCheckOptions& o) {
  if (!o.enabled) return "off";
  return fmt::format("on (threshold {}, noise_px {}, sigma_factor {}, min_neighbours {})",
                     o.threshold, o.noise_px, o.sigma_factor, o.min_neighbours);
}

void ContinuityCheckOptions::Check() const {
  CheckValue(kMinMisfitRange.Contains(min_misfit), "dic.continuity.min_misfit", Num(min_misfit),
             "in " + kMinMisfitRange.Text());
  for (const ContinuityLimit& limit : kContinuityLimits) {
    const double value = this->*limit.field;
    CheckValue(value > limit.above, std::string("dic.continuity.") + limit.name, Num(value),
               limit.Expected());
  }
}

std::string ContinuityLimit::Expected() const {
  return fmt::format("a number > {}{}, or none ({})", above,
                     *unit == '\0' ? "" : std::string(" ") + unit, when_none);
}

double ContinuityLimit::FromString(const std::string& text, const std::string& where) const {
  if (text == "none") return std::numeric_limits<double>::infinity();
  const std::optional<double> value = ParseNumber(text);
  CheckValue(value && *value > above && std::isfinite(*value), where, text, Expected());
  return *value;
}

const ContinuityLimit& ContinuityLimitOf(double ContinuityCheckOptions::*field) {
  const auto* limit = std::find_if(kContinuityLimits.begin(), kContinuityLimits.end(),
                                   [field](const ContinuityLimit& l) { return l.field == field; });
  assert(limit != kContinuityLimits.end() && "not a threshold of ContinuityCheckOptions");
  return *limit;
}

std::string ContinuityCheckText(const ContinuityCheckOptions& c) {
  if (!c.enabled) return "off";
  return fmt::format(
      "on (misfit_ratio {}, min_misfit {}, max_second_difference_px {}, "
      "max_neighbour_difference_px {}, local_ratio {})",
      c.misfit_ratio, c.min_misfit, c.max_second_difference_px, c.max_neighbour_difference_px,
      c.local_ratio);
}

std::string ContinuityLimitText(double limit) {
  return std::isfinite(limit) ? fmt::format("{}", limit) : "none";
}

bool OnOffFromString(const std::string& text, const std::string& where) {
  if (text == "on" || text == "true") return true;
  if (text == "off" || text == "false") return false;
  throw Error(ErrorKind::kInvalidValue, where, text, "on or off");
}

void DicOptions::Check() const {
  grid.Check();
  init.Check();
  icgn.Check();
  update.Check();
  continuity.Check();
  outliers.Check();
  CheckValue(
      data_bits == 0 || data_bits == 8 || data_bits == 10 || data_bits == 12 || data_bits == 16,
      "data_bits", std::to_string(data_bits), "0 (measured), 8, 10, 12 or 16");
}

}  // namespace impactdic
