// The documents cannot rot: every relative link of README.md and docs/ resolves (the file, and the
// heading an #anchor names), every --flag the documents quote is an option of some command, the
// command reference (docs/commands.md) is the commands' own --help, and the stage graph of
// docs/architecture.md names every stage the pipeline has. Run with IMPACTDIC_UPDATE_DOCS=1 to
// rewrite the generated pages (docs/commands.md) after changing a command.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../core/test_paths.h"
#include "cli_runner.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

const fs::path kRoot = impactdic::SourceDir();

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// README.md and every page under docs/ (sub-folders too), relative to the root.
std::vector<fs::path> Pages() {
  std::vector<fs::path> pages = {"README.md"};
  for (const auto& e : fs::recursive_directory_iterator(kRoot / "docs")) {
    if (e.is_regular_file() && e.path().extension() == ".md") {
      pages.push_back(fs::relative(e.path(), kRoot));
    }
  }
  std::sort(pages.begin(), pages.end());
  return pages;
}

// A page split into prose lines (code spans kept) and fenced code blocks (by line).
struct Page {
  std::vector<std::pair<int, std::string>> prose;  // (line number, text)
  std::vector<std::pair<int, std::string>> code;   // lines inside ``` fences
};

Page Split(const std::string& text) {
  Page page;
  bool fenced = false;
  int number = 0;
  for (const std::string& line : Lines(text)) {
    ++number;
    const std::size_t b = line.find_first_not_of(' ');
    if (b != std::string::npos && line.compare(b, 3, "```") == 0) {
      fenced = !fenced;
      continue;
    }
    (fenced ? page.code : page.prose).emplace_back(number, line);
  }
  return page;
}

// GitHub's anchor of a heading: lower case, spaces to '-', every character but letters, digits,
// '-' and '_' dropped; a repeated anchor gets -1, -2, ...
std::set<std::string> Anchors(const std::string& text) {
  std::set<std::string> anchors;
  std::map<std::string, int> seen;
  static const std::regex kId(R"(<a (?:id|name)="([^"]+)\")");
  for (const auto& [number, line] : Split(text).prose) {
    std::smatch m;
    if (std::regex_search(line, m, kId)) anchors.insert(m[1]);
    if (line.empty() || line[0] != '#') continue;
    std::string title = line.substr(line.find_first_not_of('#'));
    std::string anchor;
    for (const unsigned char c : title) {
      if (std::isalnum(c) || c == '-' || c == '_' || c >= 0x80) {
        anchor += static_cast<char>(std::tolower(c));
      } else if (c == ' ') {
        anchor += '-';
      }
    }
    anchor = anchor.substr(anchor.find_first_not_of('-') == std::string::npos
                               ? anchor.size()
                               : anchor.find_first_not_of('-'));
    const int n = seen[anchor]++;
    anchors.insert(n == 0 ? anchor : anchor + "-" + std::to_string(n));
  }
  return anchors;
}

// The broken relative links of `text` (the page at `page`, relative to `root`): "LINE: TARGET
// (why)". Links in code are not links; http(s) and mailto links are not checked.
std::vector<std::string> BrokenLinks(const fs::path& root, const fs::path& page,
                                     const std::string& text) {
  static const std::regex kLink(R"(!?\[[^\]]*\]\(([^)\s]+)(?:\s+"[^"]*")?\))");
  static const std::regex kSpan("`[^`]*`");
  std::vector<std::string> broken;
  for (const auto& [number, raw] : Split(text).prose) {
    const std::string line = std::regex_replace(raw, kSpan, "``");
    for (std::sregex_iterator it(line.begin(), line.end(), kLink), end; it != end; ++it) {
      const std::string target = (*it)[1];
      if (target.rfind("http://", 0) == 0 || target.rfind("https://", 0) == 0 ||
          target.rfind("mailto:", 0) == 0) {
        continue;
      }
      const std::size_t hash = target.find('#');
      const std::string file = target.substr(0, hash);
      const fs::path resolved =
          file.empty() ? root / page : (root / page).parent_path() / fs::path(file);
      const std::string where = page.string() + ":" + std::to_string(number) + ": " + target;
      if (!fs::exists(resolved)) {
        broken.push_back(where + " (no such file)");
        continue;
      }
      if (hash == std::string::npos) continue;
      if (resolved.extension() != ".md") {
        broken.push_back(where + " (an anchor into a file that is not markdown)");
        continue;
      }
      const std::string anchor = target.substr(hash + 1);
      const std::string linked = file.empty() ? text : ReadText(resolved);
      if (!Anchors(linked).count(anchor)) broken.push_back(where + " (no such heading)");
    }
  }
  return broken;
}

TEST(DocsLinks, TheCheckFindsAMissingFileAndAMissingHeading) {
  const std::string text =
      "# Title\n\n## A section, with `code`\n\n[ok](#a-section-with-code) [ok](README.md)\n"
      "[gone](no_such_page.md) [bad](#no-such-heading) [ok](https://example.org/x)\n"
      "```\n[not a link](nowhere.md)\n```\n";
  const std::vector<std::string> broken = BrokenLinks(kRoot, "README.md", text);
  ASSERT_EQ(broken.size(), 2u) << ::testing::PrintToString(broken);
  EXPECT_NE(broken[0].find("no_such_page.md (no such file)"), std::string::npos);
  EXPECT_NE(broken[1].find("#no-such-heading (no such heading)"), std::string::npos);
}

TEST(DocsLinks, EveryRelativeLinkResolves) {
  std::vector<std::string> broken;
  for (const fs::path& page : Pages()) {
    for (const std::string& b : BrokenLinks(kRoot, page, ReadText(kRoot / page))) {
      broken.push_back(b);
    }
  }
  EXPECT_TRUE(broken.empty()) << "broken links:\n" << ::testing::PrintToString(broken);
}

// --- The flags -----------------------------------------------------------------------------

// The subcommands, as `impactdic` without arguments lists them ("  NAME  description").
std::vector<std::string> Subcommands() {
  const CliResult r = RunCli("");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::vector<std::string> names;
  static const std::regex kLine(R"(^  ([a-z][a-z-]*)  +\S)");
  for (const std::string& line : Lines(r.output)) {
    std::smatch m;
    if (std::regex_search(line, m, kLine)) names.push_back(m[1]);
  }
  return names;
}

// `impactdic SUB --help` of every subcommand, and the top level's.
const std::map<std::string, std::string>& Helps() {
  static const std::map<std::string, std::string> helps = [] {
    std::map<std::string, std::string> h;
    for (const std::string& sub : Subcommands()) {
      const CliResult r = RunCli(sub + " --help");
      EXPECT_EQ(r.exit_code, 0) << sub << ": " << r.output;
      h[sub] = r.output;
    }
    h[""] = RunCli("--help").output;
    return h;
  }();
  return helps;
}

// Every --flag any --help lists.
std::set<std::string> HelpFlags() {
  std::set<std::string> flags;
  static const std::regex kFlag(R"((?:^|[\s,\[])(--[A-Za-z0-9][A-Za-z0-9._-]*))");
  for (const auto& [sub, help] : Helps()) {
    for (std::sregex_iterator it(help.begin(), help.end(), kFlag), end; it != end; ++it) {
      flags.insert((*it)[1]);
    }
  }
  return flags;
}

// Flags of other programs that the documents quote bare, with the file that defines each (the
// test checks the flag is there, so this list cannot outlive the option).
const std::map<std::string, std::string>& OtherProgramsFlags() {
  static const std::map<std::string, std::string> flags = {
      {"--anchor", "bench/pair_benchmark.py"},
      {"--anchor-via", "bench/pair_benchmark.py"},
      // Slurm's sbatch, as the job-array test submits it.
      {"--array", "tests/pipeline/slurm_campaign_test.sh"},
      {"--cpus-per-task", "tests/pipeline/slurm_campaign_test.sh"},
      {"--kill-on-invalid-dep", "tests/pipeline/slurm_campaign_test.sh"},
      {"--parsable", "tests/pipeline/slurm_campaign_test.sh"},
      {"--cache", "bench/dic_throughput_benchmark.cc"},
      {"--check", "bench/dic_challenge.py"},
      {"--cli", "bench/python_overhead.py"},
      {"--data", "bench/dic_challenge.py"},
      {"--diagonal", "bench/dic_bias_benchmark.cc"},
      {"--json", "bench/dic_challenge.py"},
      {"--psf", "bench/dic_bias_benchmark.cc"},
      {"--quick", "bench/dic_challenge.py"},
      {"--runs", "bench/startup_benchmark.py"},
      {"--sand-roi", "bench/dic_challenge.py"},
      {"--tone", "bench/reference_update_benchmark.cc"},
      {"--work", "bench/dic_challenge.py"},
  };
  return flags;
}

// Whether a code span or code line quotes a command of ours: its program (after VAR=value
// assignments) is `impactdic` under any path, or it starts with a subcommand's name (`run -o`,
// `campaign --jobs`) or with a flag (`--threads`).
bool QuotesOurCommand(const std::string& code, const std::vector<std::string>& subcommands) {
  std::stringstream words(code);
  std::string first;
  while (words >> first && first.find('=') != std::string::npos && first.rfind("--", 0) != 0) {
  }
  if (first.rfind("--", 0) == 0) return true;
  if (first == "impactdic" ||
      (first.size() > 10 && first.substr(first.size() - 10) == "/impactdic")) {
    return true;
  }
  return std::find(subcommands.begin(), subcommands.end(), first) != subcommands.end();
}

// The --flags quoted in `text` (code spans and code lines that quote a command of ours, see
// QuotesOurCommand) that no --help lists: "PAGE:LINE: --flag". A placeholder (`--dic.KEY`,
// `--continuity-*`) must be the start of some flag.
std::vector<std::string> UnknownFlags(const std::string& page, const std::string& text,
                                      const std::set<std::string>& known,
                                      const std::vector<std::string>& subcommands) {
  static const std::regex kSpan("`([^`]+)`");
  static const std::regex kFlag(R"((?:^|[\s\[(=|,])(--[a-z][A-Za-z0-9._*-]*))");
  std::vector<std::pair<int, std::string>> quotes;
  const Page split = Split(text);
  for (const auto& [number, line] : split.prose) {
    for (std::sregex_iterator it(line.begin(), line.end(), kSpan), end; it != end; ++it) {
      quotes.emplace_back(number, (*it)[1]);
    }
  }
  bool continued = false;  // A code line ending in '\' continues the command.
  for (const auto& [number, line] : split.code) {
    const std::string code = line.substr(std::min(line.size(), line.find_first_not_of(' ')));
    if (continued || QuotesOurCommand(code, subcommands)) quotes.emplace_back(number, code);
    continued =
        !line.empty() && line.back() == '\\' && (continued || QuotesOurCommand(code, subcommands));
  }
  std::vector<std::string> unknown;
  for (const auto& [number, quote] : quotes) {
    if (!QuotesOurCommand(quote, subcommands) && quote.find(" --") != std::string::npos &&
        quote.rfind("--", 0) != 0) {
      continue;  // Another program's command line (cmake --build, ctest --preset).
    }
    for (std::sregex_iterator it(quote.begin(), quote.end(), kFlag), end; it != end; ++it) {
      std::string flag = (*it)[1];
      while (!flag.empty() && (flag.back() == '.' || flag.back() == '-')) flag.pop_back();
      std::size_t placeholder = flag.find('*');
      for (std::size_t i = 2; i < flag.size() && i < placeholder; ++i) {
        if (std::isupper(static_cast<unsigned char>(flag[i]))) placeholder = i;
      }
      bool found = known.count(flag) > 0 || OtherProgramsFlags().count(flag) > 0;
      if (!found && placeholder < flag.size()) {
        const std::string prefix = flag.substr(0, placeholder);
        found = std::any_of(known.begin(), known.end(),
                            [&](const std::string& k) { return k.rfind(prefix, 0) == 0; });
      }
      if (!found) unknown.push_back(page + ":" + std::to_string(number) + ": " + flag);
    }
  }
  return unknown;
}

TEST(DocsFlags, TheCheckFindsAFlagNoCommandHas) {
  const std::set<std::string> known = {"--threads", "--dic.subset_size", "--force"};
  const std::string text =
      "Use `--threads 2`, `run --force`, `--dic.KEY V` and `cmake --build x`; `--no-such-flag`.\n"
      "```sh\nimpactdic run s.yaml --threads 2 \\\n  --made-up 1\ncmake --preset x\n```\n";
  const std::vector<std::string> unknown = UnknownFlags("p.md", text, known, {"run"});
  EXPECT_EQ(unknown, (std::vector<std::string>{"p.md:1: --no-such-flag", "p.md:4: --made-up"}));
}

TEST(DocsFlags, EveryQuotedFlagIsAnOptionOfSomeCommand) {
  const std::set<std::string> known = HelpFlags();
  ASSERT_TRUE(known.count("--threads") && known.count("--dic.subset_size")) << "help not read";
  const std::vector<std::string> subcommands = Subcommands();
  std::vector<std::string> unknown;
  for (const fs::path& page : Pages()) {
    for (const std::string& u :
         UnknownFlags(page.string(), ReadText(kRoot / page), known, subcommands)) {
      unknown.push_back(u);
    }
  }
  EXPECT_TRUE(unknown.empty()) << "flags no command has:\n" << ::testing::PrintToString(unknown);
  for (const auto& [flag, file] : OtherProgramsFlags()) {
    EXPECT_NE(ReadText(kRoot / file).find(flag), std::string::npos) << flag << " in " << file;
  }
}

// --- Generated pages -----------------------------------------------------------------------

// The generated command reference: docs/commands.md (the top level's --help and one line per
// command, linking its page) and docs/commands/COMMAND.md (its --help), in the order `impactdic`
// lists the commands.
std::map<std::string, std::string> CommandReference() {
  const std::string generated =
      "<!-- Generated from `impactdic --help` and `impactdic COMMAND --help` by\n"
      "`IMPACTDIC_UPDATE_DOCS=1 build/release/tests/cli/cli_docs_test "
      "--gtest_filter='DocsReference.*'`;\nthe test fails when this page is out of date. -->\n\n";
  std::map<std::string, std::string> pages;
  std::string index = "# Command reference\n\n" + generated +
                      "Every option of every command, as its `--help` prints it. How options, "
                      "scene-key flags, errors,\noutput files and output folders work: "
                      "[command_line.md](command_line.md); every scene key:\n"
                      "[scene_keys.md](scene_keys.md).\n\n| command | options |\n|---|---|\n";
  for (const std::string& sub : Subcommands()) {
    index += "| `impactdic " + sub + "` | [commands/" + sub + ".md](commands/" + sub + ".md) |\n";
    pages["docs/commands/" + sub + ".md"] = "# `impactdic " + sub + "`\n\n" + generated +
                                            "All commands: [commands.md](../commands.md).\n\n"
                                            "```text\n" +
                                            Helps().at(sub) + "```\n";
  }
  index += "\n## `impactdic`\n\n```text\n" + Helps().at("") + "```\n";
  pages["docs/commands.md"] = index;
  return pages;
}

void ExpectGenerated(const std::string& relative, const std::string& expected) {
  const fs::path path = kRoot / relative;
  if (std::getenv("IMPACTDIC_UPDATE_DOCS")) {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << expected;
  }
  EXPECT_EQ(ReadText(path), expected) << relative << " is out of date; regenerate it:\n"
                                      << "IMPACTDIC_UPDATE_DOCS=1 build/release/tests/cli/"
                                         "cli_docs_test --gtest_filter='DocsReference.*'";
}

TEST(DocsReference, CommandReferenceIsTheCommandsHelp) {
  const std::map<std::string, std::string> pages = CommandReference();
  for (const auto& [page, text] : pages) ExpectGenerated(page, text);
  // No page of a command that no longer exists.
  for (const auto& e : fs::directory_iterator(kRoot / "docs/commands")) {
    const std::string relative = fs::relative(e.path(), kRoot).string();
    EXPECT_TRUE(pages.count(relative)) << relative << " is no command's page: remove it";
  }
}

// The stage graph of docs/architecture.md (its ```mermaid block) has a node for every stage of
// the pipeline (AllSceneStages, and analyze's load_dic) and no other.
TEST(DocsReference, StageGraphNamesEveryStage) {
  const std::string text = ReadText(kRoot / "docs/architecture.md");
  const std::size_t begin = text.find("```mermaid\n");
  ASSERT_NE(begin, std::string::npos) << "no ```mermaid block in docs/architecture.md";
  const std::string graph = text.substr(begin, text.find("```\n", begin + 10) - begin);
  std::set<std::string> nodes;
  static const std::regex kNode(R"(\b([a-z_]+)\[)");
  for (std::sregex_iterator it(graph.begin(), graph.end(), kNode), end; it != end; ++it) {
    nodes.insert((*it)[1]);
  }
  std::set<std::string> stages(AllSceneStages().begin(), AllSceneStages().end());
  stages.insert("load_dic");
  EXPECT_EQ(nodes, stages) << graph;
}

}  // namespace
}  // namespace impactdic
