// impactdic: command-line entry point. Parses the global options, dispatches to a subcommand and
// turns every error into one message on stderr and a non-zero exit code. SIGINT, SIGTERM and
// SIGHUP remove the temporaries of the outputs in progress and exit with 128 + signal
// (core/interrupt.h).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstddef>
#include <exception>
#include <iostream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/log.h"
#include "impactdic/core/threads.h"

namespace {

// CLI11 says "Could not convert: --mass = abc"; add what the option takes ("a number").
std::string ConversionMessage(const CLI::App& app, const CLI::ConversionError& e) {
  std::string message = e.what();
  const std::string head = "Could not convert: ";
  const std::size_t eq = message.find(" = ");
  if (message.rfind(head, 0) != 0 || eq == std::string::npos) return message;
  const std::string name = message.substr(head.size(), eq - head.size());
  std::string type;
  // The parsed subcommand's option first (an option name can mean different things in two).
  for (const CLI::App* sub : app.get_subcommands({})) {
    const CLI::Option* option = sub->get_option_no_throw(name);
    if (option != nullptr && (type.empty() || sub->parsed())) type = option->get_type_name();
  }
  const std::string what = type == "INT"     ? "an integer"
                           : type == "UINT"  ? "a non-negative integer"
                           : type == "FLOAT" ? "a number"
                                             : "a value of type " + type;
  return "invalid value for " + name + " (got '" + message.substr(eq + 3) + "'); expected " +
         (type.empty() ? std::string("a value of the option's type") : what);
}

int Main(int argc, char** argv) {
  using namespace impactdic;
  CLI::App app{
      "impactdic: DIC of pounder impacts on sand, momentum validation and the added-mass impact "
      "model",
      "impactdic"};  // The name in every usage line, whatever path the binary was started by.
  app.require_subcommand(1);
  app.set_version_flag(
      "-V,--version", [] { return cli::VersionText(); },
      "Print the version, the git commit and the SIMD kernels, and exit");
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "More log output (debug level)");
  app.add_flag("-q,--quiet", quiet, "Only warnings and errors");
  app.parse_complete_callback([&] {
    SetLogLevel(verbose ? LogLevel::kDebug : quiet ? LogLevel::kWarning : LogLevel::kInfo);
    cli::CheckOneNamePerOption(app);  // Before any command runs.
  });

  // The commands. Each adds hundreds of options (the scene keys' flags): all of them take about
  // 4 ms to set up, a visible share of a one-pair `correlate`. So only the command the first word
  // names is set up; every one for the command table, --help and a word that names none.
  struct Command {
    const char* name;
    void (*add)(CLI::App&);
  };
  static constexpr Command kCommands[] = {
      {"run", cli::RegisterRunCommand},
      {"synth", cli::RegisterSynthCommand},
      {"calibrate", cli::RegisterCalibrateCommand},
      {"correlate", cli::RegisterCorrelateCommand},
      {"analyze", cli::RegisterAnalyzeCommand},
      {"model", cli::RegisterModelCommand},
      {"render", cli::RegisterRenderCommand},
      {"campaign", cli::RegisterCampaignCommand},
      {"validate-dem", cli::RegisterValidateDemCommand},
      {"version", cli::RegisterVersionCommand},
      {"init", cli::RegisterInitCommand},
  };
  const auto* word =
      std::find_if(argv + 1, argv + argc, [](const char* a) { return a[0] != '-' && a[0] != 0; });
  const auto* named = std::find_if(std::begin(kCommands), std::end(kCommands), [&](const auto& c) {
    return word != argv + argc && std::string(c.name) == *word;
  });
  for (const Command& c : kCommands) {
    if (named != std::end(kCommands) && &c != named) continue;
    c.add(app);
    const std::vector<CLI::App*> added = app.get_subcommands({});
    if (added.empty() || added.back()->get_name() != c.name)
      throw std::logic_error(std::string("main.cc: the command table's '") + c.name +
                             "' is not the name its Register function gives");
  }
  cli::PrepareOneNamePerOption(&app);

  // No arguments: what the tool can do, not an error.
  if (argc == 1) {
    std::cout << cli::CommandTable(app);
    return 0;
  }

  // An unknown first word is reported as such (CLI11 would only say a subcommand is required).
  std::string names;
  bool known = word == argv + argc;
  for (const auto* sub : app.get_subcommands({})) {
    names += (names.empty() ? "" : ", ") + sub->get_name();
    known = known || sub->get_name() == *word;
  }
  if (!known) {
    std::cerr << "impactdic: error: unknown subcommand '" << *word
              << "'; expected one of: " << names << "\n";
    return 1;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    std::cout << e.what();  // VersionText(), ending in a newline.
    return 0;
  } catch (const CLI::ConversionError& e) {
    std::cerr << "impactdic: error: " << ConversionMessage(app, e) << "\n";
    std::cerr << "Run with --help for the allowed options.\n";
    return 1;
  } catch (const CLI::ParseError& e) {
    std::cerr << "impactdic: error: " << e.what() << "\n";
    if (e.get_exit_code() == 0) return 0;
    std::cerr << "Run with --help for the allowed options.\n";
    return 1;
  } catch (const Error& e) {
    WaitIfInterrupted();  // Not an error of its own: the interruption's message comes instead.
    std::cerr << "impactdic: error: " << e.what() << "\n";
    return ExitCode(e.kind());
  } catch (const std::exception& e) {
    WaitIfInterrupted();
    std::cerr << "impactdic: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const impactdic::WorkerThreadsJoinedAtExit workers;
    impactdic::InstallInterruptCleanup();
    const int exit_code = Main(argc, argv);
    // An error caused by a signal (a write that failed as the cleanup removed its folder) must
    // not race the cleanup: the cleanup thread ends the process with 128 + signal.
    impactdic::WaitIfInterrupted();
    return exit_code;
  } catch (const std::exception& e) {
    // Setting up the commands or the interrupt cleanup failed (a programming error or no memory):
    // Main catches everything that runs a command.
    std::cerr << "impactdic: internal error: " << e.what() << "\n";
    return 1;
  } catch (...) {
    std::cerr << "impactdic: internal error\n";
    return 1;
  }
}
