// The commented scene template `impactdic init` writes: every key of the scene's option tables
// (SceneOptionTables, pipeline/scene.h) with its library default, its unit, range and meaning,
// and the inputs a researcher must give marked `# REQUIRED`.
//
//   WriteTextFileAtomic("test12/scene.yaml", SceneTemplate());
//   // edit test12/scene.yaml, then: impactdic run test12/scene.yaml
//
// The template is generated from the tables, so a key added to them appears in it. It parses as
// written (ParseScene) with the library's defaults; the REQUIRED placeholders (e.g. inputs.frames
// "frames/*.png") are what the researcher replaces.
#ifndef IMPACTDIC_PIPELINE_SCENE_TEMPLATE_H_
#define IMPACTDIC_PIPELINE_SCENE_TEMPLATE_H_

#include <string>

namespace impactdic {

// The placeholder of inputs.frames in the template (a glob relative to the scene file's folder).
inline constexpr const char* kSceneTemplateFramesPlaceholder = "frames/*.png";

// The scene template's YAML text (see above).
std::string SceneTemplate();

// `impactdic init`: writes FOLDER/scene.yaml (the folder created if missing) and returns its path.
// Error when the folder cannot be made, or when the file exists and not `force`.
std::string WriteSceneTemplate(const std::string& folder, bool force);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_SCENE_TEMPLATE_H_
