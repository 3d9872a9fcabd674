// The one way YAML files are loaded: scene files (io/scene.h), calibration files (calib) and
// synthetic scene specs (synth).
//
//   const YAML::Node root = LoadYamlFile("camera.yaml", "a calibration file (YAML)");
//
// Besides YAML syntax errors (Error kFileFormat with file:line:column), it refuses
//  - a key given twice in one map: yaml-cpp would silently keep the first value. The error names
//    the key path and both lines ("test.mass_kg ... at line 9 (first at line 3)");
//  - a file that is not text, e.g. an image given as the calibration: the error names its kind.
// `what` says what the file should be, for messages ("a scene file (YAML)").
#ifndef IMPACTDIC_IO_YAML_H_
#define IMPACTDIC_IO_YAML_H_

#include <yaml-cpp/yaml.h>

#include <string>

namespace impactdic {

// Parses the first document of `text`, read from `path` (for messages).
YAML::Node LoadYaml(const std::string& text, const std::string& path, const std::string& what);

// ReadInputFile(path, what, kMaxTextFileBytes) (a regular file of at most 64 MiB), then LoadYaml.
YAML::Node LoadYamlFile(const std::string& path, const std::string& what);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_YAML_H_
