// Test helper: a command refuses a flag's value exactly as the library check behind the flag
// does (the option's one definition), with the library's expected text, naming the flag.
#ifndef IMPACTDIC_TESTS_CLI_EXPECT_FLAG_ERROR_H_
#define IMPACTDIC_TESTS_CLI_EXPECT_FLAG_ERROR_H_

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "cli_runner.h"
#include "impactdic/core/error.h"

namespace impactdic {

// Expects `library_check` to throw an impactdic::Error and the command's `result` to be exit 1
// with "FLAG: invalid value ...; expected <that error's expected text>".
inline void ExpectFlagRefusedAsTheLibraryDoes(const CliResult& result, const std::string& flag,
                                              const std::function<void()>& library_check) {
  std::string expected;
  try {
    library_check();
  } catch (const Error& e) {
    expected = e.expected();
  }
  ASSERT_FALSE(expected.empty()) << "the library accepts what " << flag << " was given";
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find(flag + ": invalid value"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("expected " + expected), std::string::npos) << result.output;
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_CLI_EXPECT_FLAG_ERROR_H_
