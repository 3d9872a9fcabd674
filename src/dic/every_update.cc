// "every:N": the frame N frames after the reference becomes the reference (docs/dic.md,
// "Reference updates").
#include <cstddef>
#include <exception>
#include <memory>
#include <string>

#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"
#include "impactdic/dic/reference_update.h"
#include "reference_update_policies.h"

namespace impactdic::internal {
namespace {

class EveryNUpdate final : public ReferenceUpdatePolicy {
 public:
  explicit EveryNUpdate(int n) : n_(n) {}
  std::string Name() const override { return "every:" + std::to_string(n_); }
  bool MakesFrameTheReference(const SolvedFrame& frame) const override {
    return frame.frame - frame.reference_frame >= n_;
  }

 private:
  int n_;
};

}  // namespace

ReferenceUpdatePolicyInfo EveryNPolicy() {
  return {"every", "every:N (N >= 1)", [](const std::string& argument, const UpdateOptions&) {
            std::size_t used = 0;
            int n = 0;
            try {
              n = std::stoi(argument, &used);
            } catch (const std::exception&) {
              used = 0;
            }
            CheckValue(used > 0 && used == argument.size() && n >= 1, "every:N", argument,
                       "an integer N >= 1");
            return std::make_unique<EveryNUpdate>(n);
          }};
}

}  // namespace impactdic::internal
