// A campaign: many scenes (e.g. the paper's 27 combinations of m_p, h and D) run one after the
// other, then the power-law regression of Eq. 4 over their measured m_add,max:
//   m_add,max = c m_p^a v0^b A^g   (paper: c = 425, a = 0.1, b = 0.2, g = 1.3)
// with 95 % confidence intervals and R^2 (momentum/fit.h).
//
//   CampaignOptions options;
//   options.output_folder = "results/campaign";
//   CampaignSummary s = RunCampaign({"t01.yaml", "t02.yaml", ...}, options);
//
// Outputs: <output_folder>/<scene name>/ (each scene's pipeline outputs), campaign.csv (one row per
// scene: name, m_p, v0, A, the key figures and eq4_fit = used | excluded), regression.json (the fit
// and, under "excluded", each scene left out with the reason).
//
// A scene whose run produced nothing usable (PipelineSummary::failures, e.g. no valid subset or
// no measurable t_e) still gets its outputs (the campaign runs scenes with allow_partial) but
// never enters the Eq. 4 fit; the report, the log and regression.json say which and why.
//
// They are one generation of the folder (io/output_generation.h): a failed or interrupted campaign
// leaves the previous one as it was. RegressCampaignTable redoes campaign.csv and regression.json
// and keeps the folder's other entries.
#ifndef IMPACTDIC_PIPELINE_CAMPAIGN_H_
#define IMPACTDIC_PIPELINE_CAMPAIGN_H_

#include <string>
#include <vector>

#include "impactdic/io/json.h"
#include "impactdic/momentum/fit.h"
#include "impactdic/pipeline/pipeline.h"

namespace impactdic {

struct CampaignOptions {
  std::string output_folder = "results/campaign";  // Created (replaced) at the end.
  int threads = -1;                                // As PipelineOptions::threads.
  double confidence = 0.95;                        // Of the regression intervals, in (0, 1).
  void Check() const;
};

struct CampaignScene {
  std::string name;
  double mass_kg = 0, velocity_m_s = 0, area_m2 = 0;
  SceneFigures figures;
  // Why the scene is left out of the Eq. 4 fit (a stage produced nothing usable, no measured
  // m_add,max, or "excluded" in an input table); empty: it is in the fit.
  std::string excluded;
};

struct CampaignSummary {
  std::vector<CampaignScene> scenes;
  bool fitted = false;
  std::string fit_note;  // Why there is no fit (too few usable scenes), if so.
  PowerLawFit fit;
  std::vector<std::string> outputs;
  double seconds = 0;
  JsonObject RegressionJson() const;
  std::string FullReport() const;
};

// Runs every scene, then the regression (needs >= 5 usable scenes with a finite m_add,max).
CampaignSummary RunCampaign(const std::vector<std::string>& scene_paths,
                            const CampaignOptions& options);

// The regression alone, from a CSV with the columns mass_kg, velocity_m_s, area_m2 and
// added_mass_max_kg (e.g. a campaign.csv, or the user's own table); rows whose optional eq4_fit
// column says "excluded" are left out.
CampaignSummary RegressCampaignTable(const std::string& csv_path, const CampaignOptions& options);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_CAMPAIGN_H_
