// Test helpers for impactdic::Error: the message a call throws, or a check that it contains a text.
#ifndef IMPACTDIC_TESTS_CORE_EXPECT_ERROR_H_
#define IMPACTDIC_TESTS_CORE_EXPECT_ERROR_H_

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "impactdic/core/error.h"

namespace impactdic {

// The message of the impactdic::Error that `f` throws, or "no error".
inline std::string ErrorText(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// Expects `f` to throw an impactdic::Error whose message contains `text`.
inline void ExpectErrorContaining(const std::function<void()>& f, const std::string& text) {
  const std::string message = ErrorText(f);
  EXPECT_NE(message, "no error") << "expected an error containing '" << text << "'";
  EXPECT_NE(message.find(text), std::string::npos) << message;
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_CORE_EXPECT_ERROR_H_
