// Editing a synthesised scene's text in the pipeline tests: read a file, replace one passage
// (a test failure when it is not there).
#ifndef IMPACTDIC_TESTS_PIPELINE_SCENE_TEXT_H_
#define IMPACTDIC_TESTS_PIPELINE_SCENE_TEXT_H_

#include <gtest/gtest.h>

#include <cstddef>
#include <fstream>
#include <sstream>
#include <string>

namespace impactdic {

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// `text` with the first `from` replaced by `to`; a failure (and `text` unchanged) without one.
inline std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_PIPELINE_SCENE_TEXT_H_
