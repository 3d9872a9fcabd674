// Realistic synthetic footage with exact truth (docs/synth.md, "Realistic mode"): what a camera
// filming a pounder entering natural sand records, rendered from known fields.
//
//  * Texture: natural sand, no painted speckle: random grains of varied size and brightness
//    (light quartz and darker minerals, each shaded by a light from the upper left, soft edges)
//    over a darker fine matrix. Like the analytic speckle (speckle.h) it is a function of the
//    material point, so a deformed image is rendered exactly (Newton inversion of x = X + u(X),
//    pixel-area supersampling), never by interpolating an image.
//  * Light: uneven illumination (a radial fall-off from a lamp at the upper left), a slow drift
//    of the brightness over time, a glare patch (static, added light that saturates the sensor).
//  * Motion blur: each frame is the mean of the images at blur_samples times spread over the
//    exposure (the sensor integrates light; saturation is applied after the integration).
//  * Noise, 8-bit quantisation and JPEG compression (the frames are written as JPEG).
//  * Kinematics of a bearing-capacity failure at penetration s(t) = V t:
//      - the soil under the footing moves down with the pounder, decaying with depth
//        (v = s g(eta), g = exp(-(eta / L_core)^2));
//      - a shear band starts at each pounder edge and runs down (width w: a tanh step of the
//        vertical displacement across |xi| = b: a pure slip, the field stays invertible);
//      - heave beside the pounder: the soil outside the band rises and is pushed outwards,
//        decaying over L_heave from the band and from the surface;
//      - the rigid pounder (width 2b) moves through the field; it occludes the soil, its bottom at
//        the depth s(t). Above the surface: a static textured background wall.
//    Panel coordinates in px: xi = X - axis (right), eta = Y - surface (down).
//
// Truth: the displacement of each subset centre from the reference frame (frame 0), as the mean
// over the exposure samples, and flags for the subsets the engine cannot be expected to measure:
// straddling the pounder edge or the sand surface (a body edge), straddling a shear band, and in
// the glare.
//
//   RealisticSceneSpec spec;               // 320 x 240, 3 frames, JPEG quality 90
//   RealisticScene scene(spec);
//   cv::Mat frame = scene.RenderFrame(1);   // CV_8U, before JPEG compression
//   RealisticTruth truth = scene.Truth(points_px, /*frame=*/1, /*half_px=*/10);
//   WriteRealisticScene(scene, "out/");     // frames/frame_NNNN.jpg, truth.h5, spec.yaml
#ifndef IMPACTDIC_SYNTH_REALISTIC_H_
#define IMPACTDIC_SYNTH_REALISTIC_H_

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic {

struct RealisticSceneSpec {
  std::string name = "realistic_impact";
  // Camera and frames.
  int width = 320, height = 240;  // [px], in [64, 8192] x [48, 8192].
  int frames = 3;                 // Frames written (frame 0 is the reference), in [2, 10000].
  double fps = 5000;              // Frame rate [1/s], > 0.
  double exposure_s = 1e-4;       // Exposure [s], in (0, 1 / fps].
  int blur_samples = 4;           // Sub-times integrated over the exposure, in [1, 32].
  int supersampling = 3;          // Samples per pixel side, in [1, 8].
  double noise_sigma = 1.5;       // Gaussian noise [grey levels of 8 bits], >= 0.
  int jpeg_quality = 90;          // JPEG quality of the written frames, in [1, 100]; 0 = PNG.
  // Sand texture.
  double grain_radius_px = 1.6;      // Mean grain radius [px], in [0.5, 20].
  double grain_radius_spread = 0.5;  // Radii uniform in r (1 +- spread), in [0, 0.9].
  double grain_coverage = 1.6;       // Grains per area times pi r^2, in (0, 5].
  // Light.
  double light_falloff = 0.35;           // Relative fall-off at the far corner, in [0, 0.9].
  double light_drift_per_frame = 0.01;   // Relative brightness change per frame, in [-0.1, 0.1].
  double glare_level = 0.9;              // Peak added light [full scale], >= 0 (0 = no glare).
  double glare_radius_px = 0;            // Glare sigma [px], >= 0; 0 = width / 30.
  double glare_x = 0.78, glare_y = 0.7;  // Glare centre [fractions of width, height], in [0, 1].
  // Geometry and kinematics [px of the image].
  double surface_fraction = 0.3;        // Sand surface at this fraction of the height, [0.05, 0.8].
  double pounder_width_fraction = 0.3;  // Pounder width 2b / image width, in [0.05, 0.8].
  double penetration_px_per_frame = 2;  // Pounder speed V [px per frame], in [0, 50].
  double shear_band_width_px = 0.5;     // w of the tanh step across the band [px], in [0.1, 20].
  double core_decay_px = 0;             // L_core [px], >= 0; 0 = 2b.
  double heave_ratio = 0.3;             // Heave amplitude / penetration, in [0, 1].
  double heave_decay_px = 0;            // L_heave [px], >= 0; 0 = b.
  // DIC grid of truth.h5 (the correlator's layout on the whole image).
  int subset_size = 21;    // Odd, in [5, 201].
  int step = 10;           // >= 1.
  std::uint64_t seed = 1;  // Grains and noise.
  // Throws Error(kInvalidValue) naming the first broken field by its YAML key.
  void Check() const;
};

// Parses a realistic spec YAML (every key optional; unknown keys are errors naming the closest):
//   realistic: {width: 320, height: 240, frames: 3, ...}   (the field names above)
RealisticSceneSpec ParseRealisticSceneSpec(const std::string& yaml_text, const std::string& path);
RealisticSceneSpec LoadRealisticSceneSpec(const std::string& path);
std::string RealisticSceneSpecToYaml(const RealisticSceneSpec& spec);

// Truth of subsets (reference centres) in one frame.
struct RealisticTruth {
  std::vector<double> u_px, v_px;                  // Displacement since frame 0 (exposure means).
  std::vector<std::uint8_t> straddles_edge;        // Pounder edge or sand surface in the subset.
  std::vector<std::uint8_t> straddles_shear_band;  // A shear band crosses the subset.
  std::vector<std::uint8_t> in_glare;              // Glare adds >= 0.2 full scale in the subset.
  std::vector<std::uint8_t> Flagged() const;       // Any of the three.
};

class RealisticScene {
 public:
  explicit RealisticScene(const RealisticSceneSpec& spec);
  const RealisticSceneSpec& spec() const { return spec_; }

  double axis_px() const { return spec_.width / 2.0; }
  double surface_px() const { return spec_.surface_fraction * spec_.height; }
  double half_width_px() const { return 0.5 * spec_.pounder_width_fraction * spec_.width; }
  // Pounder penetration [px] at time t [s] (frame k starts its exposure at k / fps).
  double Penetration(double t_s) const;
  // Soil displacement [px] at material point (X, Y) [px] and time t.
  cv::Vec2d SoilDisplacement(double X, double Y, double t_s) const;
  // Sand brightness (before light) at a material point, in [0, 1].
  double SandIntensity(double X, double Y) const;

  // Frame k (CV_8U, noise included, before JPEG). with_noise = false: the noise-free frame.
  cv::Mat RenderFrame(int k, bool with_noise = true) const;
  // Truth for subsets of half size half_px centred at reference pixels `points`.
  RealisticTruth Truth(const std::vector<cv::Point2d>& points, int k, double half_px) const;
  // The correlator's grid on the whole image for the spec's subset_size and step (row-major).
  std::vector<cv::Point2d> GridPoints(int* cols, int* rows) const;

 private:
  struct Impl;
  cv::Vec2d MeanDisplacement(double X, double Y, int k) const;
  bool ReferencePoint(double x, double y, double* X, double* Y) const;
  RealisticSceneSpec spec_;
  std::shared_ptr<const Impl> impl_;
};

struct RealisticSceneReport {
  std::string out_dir, truth_h5;
  int frames = 0;
  double render_seconds = 0;
};

// Writes frames/frame_NNNN.jpg (.png with jpeg_quality 0), truth.h5 and spec.yaml into out_dir
// (created if missing; each file written atomically, truth.h5 last).
RealisticSceneReport WriteRealisticScene(const RealisticScene& scene, const std::string& out_dir);

}  // namespace impactdic

#endif  // IMPACTDIC_SYNTH_REALISTIC_H_
