// The number of worker threads: one rule for every command, option and scene key.
//   0      all cores (the default)
//   N >= 1 at most N threads
// Anything else (e.g. -1) is an error naming the option.
#ifndef IMPACTDIC_CORE_THREADS_H_
#define IMPACTDIC_CORE_THREADS_H_

#include <string>

namespace impactdic {

// What a thread count may be, for messages and help texts.
inline constexpr const char* kThreadCountExpected = "0 (all cores) or a number of threads >= 1";

inline bool IsValidThreadCount(int threads) { return threads >= 0; }

// Error(kInvalidValue, where, threads, kThreadCountExpected) unless IsValidThreadCount(threads).
void CheckThreadCount(int threads, const std::string& where);

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_THREADS_H_
