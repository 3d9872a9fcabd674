// DicSummary's reports.
#include <fmt/format.h>

#include <cstddef>
#include <string>

#include "impactdic/dic/correlator.h"

namespace impactdic {

double DicSummary::SubsetsPerSecond() const {
  return seconds_total > 0 ? double(subsets) * frames / seconds_total : 0;
}

std::string DicSummary::BriefReport() const {
  return fmt::format(
      "{} subsets x {} frames: {:.2f}% valid, {:.2f} iterations/subset, {} reference updates, "
      "{:.3f} s ({:.0f} subsets/s){}{}{}",
      subsets, frames, 100 * valid_fraction, mean_iterations, reference_updates, seconds_total,
      SubsetsPerSecond(),
      data_bits == 10 || data_bits == 12 ? fmt::format("; {}-bit data in 16-bit images", data_bits)
                                         : "",
      Discontinuous() > 0 ? fmt::format("; {} subset results flagged as straddling a "
                                        "discontinuity",
                                        Discontinuous())
                          : "",
      Outliers() > 0 ? fmt::format("; {} subset results flagged as outliers", Outliers()) : "");
}

std::string DicSummary::NothingUsable(const std::string& min_zncc_name, double min_zncc) const {
  if (frames == 0 || valid_fraction > 0) return "";
  std::size_t most = 0;
  long long total = 0;
  for (std::size_t i = 0; i < status_counts.size(); ++i) {
    total += status_counts[i];
    if (status_counts[i] > status_counts[most]) most = i;
  }
  return fmt::format(
      "no valid subset in any of the {} frames after the reference ({} subsets; most common "
      "status: {} in {} of {} results; {} = {})",
      frames, subsets, ToString(static_cast<SubsetStatus>(most)), status_counts[most], total,
      min_zncc_name, min_zncc);
}

long long DicSummary::Outliers() const {
  return status_counts[static_cast<int>(SubsetStatus::kOutlier)];
}

long long DicSummary::Discontinuous() const {
  return status_counts[static_cast<int>(SubsetStatus::kDiscontinuous)];
}

std::string DicSummary::FullReport() const {
  std::string s = BriefReport() + "\n";
  s += fmt::format(
      "  time: coefficients {:.3f} s, reference {:.3f} s, initial guess {:.3f} s ({} searches), "
      "IC-GN {:.3f} s\n",
      seconds_coefficients, seconds_reference, seconds_initial_guess, searches, seconds_icgn);
  if (data_bits > 0)
    s += fmt::format("  data: {}-bit (saturation at grey level {})\n", data_bits,
                     (1 << data_bits) - 1);
  if (orphan_reference_bytes > 0)
    s += fmt::format("  lost subsets: at most {:.1f} kB of earlier references kept for them\n",
                     orphan_reference_bytes / 1024.0);
  s += "  status:";
  for (int i = 0; i < kSubsetStatusCount; ++i) {
    if (status_counts[i] > 0)
      s += fmt::format(" {}={}", ToString(static_cast<SubsetStatus>(i)), status_counts[i]);
  }
  return s;
}

}  // namespace impactdic
