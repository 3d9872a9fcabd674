// `impactdic version`, `impactdic --version` / `-V`: what this binary is (VersionText), and the
// command table that `impactdic` without arguments prints (CommandTable).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstddef>
#include <iostream>
#include <string>

// The IC-GN kernels are chosen inside the dic module; the CLI only reports the choice, through
// the module's own accessor (the same one its kernel tests use).
#include "../dic/icgn_kernels.h"
#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/core/version.h"

#ifndef IMPACTDIC_DIC_KERNELS_BUILT
#error "IMPACTDIC_DIC_KERNELS_BUILT is set by src/cli/CMakeLists.txt from src/dic's kernel list"
#endif

namespace impactdic::cli {

std::string VersionText() {
  using internal::DicKernel;
  std::string text = std::string("impactdic ") + Version() + " (git " + GitRevision() + ")\n";
  const std::string commit = GitCommit();
  text += "git commit: " +
          (commit == "unknown" ? std::string("unknown (built outside a git checkout)") : commit) +
          "\n";
  std::string runs;
  for (const DicKernel kernel : {DicKernel::kScalar, DicKernel::kAvx2, DicKernel::kAvx512}) {
    if (internal::DicKernelAvailable(kernel)) {
      runs += (runs.empty() ? "" : ", ") + std::string(internal::ToString(kernel));
    }
  }
  std::string in_use;
  try {
    in_use = internal::ToString(internal::ActiveIcgnKernel().kind);
  } catch (const Error& e) {  // IMPACTDIC_DIC_KERNEL names a kernel this binary cannot run.
    in_use = std::string("none: ") + e.what();
  }
  text += std::string("SIMD kernels (IC-GN): built ") + IMPACTDIC_DIC_KERNELS_BUILT +
          "; this CPU runs " + runs + "; in use " + in_use +
          " (IMPACTDIC_DIC_KERNEL=scalar|avx2|avx512 forces one)\n";
  return text;
}

std::string CommandTable(const CLI::App& app) {
  std::size_t width = 0;
  for (const CLI::App* sub : app.get_subcommands({})) {
    width = std::max(width, sub->get_name().size());
  }
  std::string text = app.get_description() + "\n\nUsage: impactdic [-v|-q] COMMAND [OPTIONS]\n\n";
  text += "Commands:\n";
  for (const CLI::App* sub : app.get_subcommands({})) {
    text += "  " + sub->get_name() + std::string(width + 2 - sub->get_name().size(), ' ') +
            sub->get_description() + "\n";
  }
  text +=
      "\n`impactdic COMMAND --help` lists a command's options; `impactdic --version` (-V) the "
      "version, commit and SIMD kernels.\nDocumentation: README.md and docs/README.md.\n";
  return text;
}

void RegisterVersionCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "version", "Print the version, the git commit and the SIMD kernels (also -V)");
  cmd->callback([] { std::cout << VersionText(); });
}

}  // namespace impactdic::cli
