#include "impactdic/dic/dic_io.h"

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>

#include <cmath>
#include <exception>
#include <filesystem>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/progress.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string Number(double v) {
  if (std::isnan(v)) return "nan";
  return fmt::format("{:.6f}", v);
}

// The frame number of image `index` (0 = the first reference): from its file name when the
// names are one numbered series, else the index itself.
long long FrameLabel(const DicResult& result, int index) {
  const auto k = static_cast<std::size_t>(index);
  return k < result.frame_numbers.size() ? result.frame_numbers[k] : index;
}

}  // namespace

DicResult CorrelateFiles(const std::vector<std::string>& paths, const DicOptions& options) {
  options.Check();
  CheckValue(paths.size() >= 2, "images", std::to_string(paths.size()) + " image(s)",
             "a reference and at least one deformed image");
  // A missing file is reported before any work; a corrupt one when it is decoded.
  for (const auto& p : paths) CheckImageFileExists(p);
  // The reference is decoded and precomputed while the first deformed image is decoded; every
  // later image is decoded while the one before it is correlated. Besides what the correlator
  // keeps (its reference and, with `auto`, the last frame), at most two images are held,
  // whatever the length of the sequence.
  Correlator correlator(options);
  DicResult result;
  result.frame_numbers = FrameNumbers(paths);
  // Colour layout of each file as decoded: read in parallel, compared in file order.
  SequenceColourCheck colour;
  std::vector<int> channels(paths.size(), 1);
  auto check_colour = [&](std::size_t k) {
    const std::string warning = colour.Check(paths[k], channels[k]);
    if (!warning.empty()) result.warnings.push_back(warning);
  };
  cv::Mat reference, current;
  std::exception_ptr reference_error, deformed_error;  // Reported in this order (deterministic).
  tbb::parallel_invoke(
      [&] {
        try {
          current = ReadGreyImage(paths[1], &channels[1]);
        } catch (...) {
          deformed_error = std::current_exception();
        }
      },
      [&] {
        try {
          reference = ReadGreyImage(paths[0], &channels[0]);
          correlator.SetReference(reference);
        } catch (...) {
          reference_error = std::current_exception();
        }
      });
  if (reference_error) std::rethrow_exception(reference_error);
  if (deformed_error) std::rethrow_exception(deformed_error);
  CheckSameSize({reference, current}, {paths[0], paths[1]});
  check_colour(0);
  check_colour(1);
  result.positions = correlator.positions();
  ProgressBar bar("correlate", paths.size() - 1);
  for (std::size_t k = 1; k < paths.size(); ++k) {
    cv::Mat next;
    tbb::task_group prefetch;
    if (k + 1 < paths.size())
      prefetch.run(
          [&next, &paths, &channels, k] { next = ReadGreyImage(paths[k + 1], &channels[k + 1]); });
    try {
      result.frames.push_back(correlator.Correlate(current));
    } catch (...) {
      prefetch.cancel();
      try {
        prefetch.wait();
      } catch (...) {  // The correlation error is the one to report.
      }
      throw;
    }
    prefetch.wait();  // Rethrows a decoding error naming the file.
    if (k + 1 < paths.size()) {
      CheckSameSize({reference, next}, {paths[0], paths[k + 1]});
      check_colour(k + 1);
    }
    current = next;
    bar.Advance();
  }
  bar.Finish();
  result.summary = correlator.summary();
  return result;
}

void WriteDicResult(const std::string& path, const DicResult& result, const DicOptions& options) {
  const std::string ext = Lower(std::filesystem::path(path).extension().string());
  const std::size_t n = result.positions.size(), frames = result.frames.size();
  if (ext == ".csv") {
    std::vector<std::vector<std::string>> rows;
    rows.reserve(n * frames);
    for (std::size_t k = 0; k < frames; ++k) {
      const FrameResult& f = result.frames[k];
      const std::string frame = std::to_string(FrameLabel(result, f.frame));
      for (std::size_t i = 0; i < n; ++i) {
        rows.push_back({frame, Number(result.positions[i].x), Number(result.positions[i].y),
                        Number(f.u_px[i]), Number(f.v_px[i]), Number(f.zncc[i]),
                        std::to_string(f.iterations[i]), ToString(f.status[i]),
                        Number(f.sigma_u_px[i]), Number(f.sigma_v_px[i])});
      }
    }
    WriteCsvRows(path,
                 {"frame", "x_px", "y_px", "u_px", "v_px", "zncc", "iterations", "status",
                  "sigma_u_px", "sigma_v_px"},
                 rows);
    return;
  }
  if (ext != ".h5" && ext != ".hdf5") {
    throw Error(ErrorKind::kInvalidValue, "output", path, "a file ending in .csv or .h5");
  }
  H5Writer out(path, /*owned_groups=*/{"/dic"});  // Other groups of an existing file stay.
  std::vector<double> x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = result.positions[i].x;
    y[i] = result.positions[i].y;
  }
  out.Write("dic/x_px", x, "px", "subset centre x in the first reference image (right)");
  out.Write("dic/y_px", y, "px", "subset centre y in the first reference image (down)");
  std::vector<double> u(n * frames), v(n * frames);
  std::vector<float> zncc(n * frames), sigma(n * frames), sigma_u(n * frames), sigma_v(n * frames);
  std::vector<std::int32_t> iterations(n * frames), status(n * frames);
  std::vector<std::int32_t> reference(frames), frame_index(frames);
  std::vector<double> frame_number(frames);
  for (std::size_t k = 0; k < frames; ++k) {
    const FrameResult& f = result.frames[k];
    reference[k] = f.reference_frame;
    frame_index[k] = f.frame;
    frame_number[k] = static_cast<double>(FrameLabel(result, f.frame));
    for (std::size_t i = 0; i < n; ++i) {
      u[k * n + i] = f.u_px[i];
      v[k * n + i] = f.v_px[i];
      zncc[k * n + i] = f.zncc[i];
      sigma[k * n + i] = f.sigma_px[i];
      sigma_u[k * n + i] = f.sigma_u_px[i];
      sigma_v[k * n + i] = f.sigma_v_px[i];
      iterations[k * n + i] = f.iterations[i];
      status[k * n + i] = static_cast<std::int32_t>(f.status[i]);
    }
  }
  const Dims dims{frames, n};
  out.Write("dic/u_px", u, dims, "px",
            "accumulated displacement x (right) of the subset centre since the first reference, "
            "NaN if the subset failed");
  out.Write("dic/v_px", v, dims, "px",
            "accumulated displacement y (down) of the subset centre since the first reference, "
            "NaN if the subset failed");
  out.Write("dic/zncc", zncc, dims, "1", "zero-normalised cross-correlation of the subset");
  out.Write("dic/sigma_px", sigma, dims, "px",
            "the larger of sigma_u_px and sigma_v_px, NaN if the subset failed");
  out.Write("dic/sigma_u_px", sigma_u, dims, "px",
            "estimated standard deviation of u against the frame's reference (least-squares "
            "covariance), NaN if the subset failed");
  out.Write("dic/sigma_v_px", sigma_v, dims, "px",
            "estimated standard deviation of v against the frame's reference (least-squares "
            "covariance), NaN if the subset failed");
  out.Write("dic/iterations", iterations, dims, "1", "IC-GN iterations");
  out.Write("dic/status", status, dims, "1", "subset status code (see attribute codes)");
  out.Write("dic/frame", frame_index, Dims{frames}, "1", "index of the deformed image (1-based)");
  out.Write("dic/frame_number", frame_number, "1",
            "frame number of the deformed image from its file name (its 1-based index when the "
            "names are not one numbered series), as the CSV's frame column");
  out.Write("dic/reference_frame", reference, Dims{frames}, "1",
            "index of the reference image each frame was correlated against (0 = first)");
  // The same attributes under the names `impactdic run` uses (status_names, shape).
  out.SetAttribute("dic/status", "codes", SubsetStatusCodes());
  out.SetAttribute("dic/status", "status_names", SubsetStatusCodes());
  out.SetAttribute("dic", "interpolation", ToString(options.icgn.interpolation));
  out.SetAttribute("dic", "shape_function", ToString(options.icgn.shape));
  out.SetAttribute("dic", "shape", ToString(options.icgn.shape));
  out.SetAttribute("dic", "reference_update",
                   options.update.mode == ReferenceUpdate::kEveryN
                       ? fmt::format("every:{}", options.update.every_n)
                       : std::string(ToString(options.update.mode)));
  out.SetAttribute("dic", "mode", ToString(options.mode));
  out.SetAttribute("dic", "max_uncertainty_px", options.icgn.max_uncertainty_px);
  out.SetAttribute("dic", "subset_size_px", options.grid.subset_size);
  out.SetAttribute("dic", "step_px", options.grid.step);
  out.SetAttribute("dic", "valid_fraction", result.summary.valid_fraction);
  out.SetAttribute("dic", "mean_iterations", result.summary.mean_iterations);
  out.SetAttribute("dic", "reference_updates", result.summary.reference_updates);
  out.Commit();
}

}  // namespace impactdic
