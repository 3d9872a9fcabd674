// The wave figures (docs/wave.md "Figures"), drawn by render when results.h5 has /wave (a run
// whose scene names base force channels, sensor.base_columns):
//  * the space-time diagram: depth below the undisturbed surface against the time after the
//    impact, colour = the centre line's downward velocity (WaveFront::space_time), with the
//    pounder's base, the fitted front (depth = c (t - t0), on the centre line the distance from
//    the impact point is the depth) and the base sensors' arrivals (onset, peak) at their depths;
//  * the base force records with their arrivals, the impact, the pounder's peak and each
//    channel's predicted return time at the surface;
//  * the displacement-depth profile along the centre line at t_e and at the last frame (log
//    scale: the exponential is a straight line) with the fits and the depth of influence.
// Each Make*Plot builds the Plot (tests and customisation); Plot* renders it with RenderPlot.
//
//   const WaveResult wave = ReadWaveResults(reader, "results.h5");
//   PlotSpaceTime(wave, "out/wave_space_time.png");
#ifndef IMPACTDIC_RENDER_WAVE_FIGURES_H_
#define IMPACTDIC_RENDER_WAVE_FIGURES_H_

#include <string>
#include <vector>

#include "impactdic/render/gnuplot.h"
#include "impactdic/sensor/wave.h"

namespace impactdic {

// Error(kInvalidValue) when wave.front has no space-time data (the front was not computed).
Plot MakeSpaceTimePlot(const WaveResult& wave);
PlotSummary PlotSpaceTime(const WaveResult& wave, const std::string& png_path,
                          const PlotOptions& options = {});

// The base records (sensor/wave.h BaseForceRecord). t_s: the records' time after the impact;
// records in wave.channels' order (matched by column).
Plot MakeBaseForcePlot(const std::vector<double>& t_s, const std::vector<BaseForceRecord>& records,
                       const WaveResult& wave);
PlotSummary PlotBaseForce(const std::vector<double>& t_s,
                          const std::vector<BaseForceRecord>& records, const WaveResult& wave,
                          const std::string& png_path, const PlotOptions& options = {});

// Error(kInvalidValue) when neither decay row has a profile.
Plot MakeDepthProfilePlot(const WaveFront& front);
PlotSummary PlotDepthProfile(const WaveFront& front, const std::string& png_path,
                             const PlotOptions& options = {});

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_WAVE_FIGURES_H_
