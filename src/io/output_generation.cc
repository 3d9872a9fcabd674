#include "impactdic/io/output_generation.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/atomic_file.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace {

enum class TemporaryKind { kNone, kTemporary, kBackup };

struct ParsedTemporary {
  TemporaryKind kind = TemporaryKind::kNone;
  std::string base;  // The name it stands for (".<base>.tmp-...").
  long pid = 0;
};

// ".<base>.tmp-<pid>-<hex>..." or ".<base>.bak-<pid>-<hex>...", <base> not empty: the rightmost
// marker followed by a valid tag.
ParsedTemporary ParseTemporary(const std::string& name) {
  if (name.size() < 2 || name[0] != '.') return {};
  for (std::size_t pos = name.size(); pos-- > 2;) {
    const std::string_view marker = std::string_view(name).substr(pos, 5);
    const bool temporary = marker == ".tmp-", backup = marker == ".bak-";
    if (!temporary && !backup) continue;
    const long pid = TemporaryTagPid(std::string_view(name).substr(pos), marker);
    if (pid > 0) {
      return {temporary ? TemporaryKind::kTemporary : TemporaryKind::kBackup,
              name.substr(1, pos - 1), pid};
    }
  }
  return {};
}

std::string Quoted(const std::vector<std::string>& names, std::size_t max_names) {
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < max_names; ++i)
    text.append(i ? ", '" : "'").append(names[i]).append("'");
  if (names.size() > max_names) text += fmt::format(" and {} more", names.size() - max_names);
  return text;
}

bool Contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// The entries a marker lists (empty if there is none).
std::set<std::string> ReadMarker(const fs::path& folder) {
  std::set<std::string> listed;
  std::ifstream in(folder / kOutputMarkerName);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') listed.insert(line);
  }
  return listed;
}

// Hard links of `from` (a file, or a folder recursively) at `to`; copies where a link cannot be
// made (another file system, no link support).
void LinkTree(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(from, ec);
  if (fs::is_symlink(st)) {
    fs::copy_symlink(from, to, ec);
  } else if (fs::is_directory(st)) {
    fs::create_directory(to, from, ec);
    if (!ec) {
      for (const auto& entry : fs::directory_iterator(from, ec))
        LinkTree(entry.path(), to / entry.path().filename());
    }
  } else if (fs::is_regular_file(st)) {
    fs::create_hard_link(from, to, ec);
    if (ec) fs::copy_file(from, to, ec);
  } else {
    return;  // Devices, sockets, pipes: not outputs of ours.
  }
  if (ec) {
    throw Error(ErrorKind::kIo, to.string(),
                "cannot keep " + from.string() + " in the new generation: " + ec.message(),
                "a writable output folder");
  }
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

// Renames `from` to `to` (an existing folder) in one step: afterwards `from` holds what `to` held.
// False with errno set when the file system or kernel cannot.
bool ExchangePaths(const std::string& from, const std::string& to) {
  return renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_EXCHANGE) == 0;
}

[[noreturn]] void SwapError(const std::string& folder, const std::string& what) {
  throw Error(ErrorKind::kIo, "output folder",
              "cannot swap the new outputs in (" + what + "); the previous outputs are unchanged",
              "a folder that can be renamed")
      .WithFile(folder);
}

// The staging folders of the generations alive in this process, with the folder each becomes:
// messages name a file by the path it will have (OutputPathForMessages).
std::mutex staged_mutex;
std::vector<std::pair<std::string, std::string>> staged_folders;  // {staging, destination as given}

}  // namespace

std::string TemporaryName(const std::string& base, const char* kind) {
  std::string name = ".";  // (Appended, not "." + ...: GCC 12 warns wrongly on that.)
  name.append(base).append(kind).append(TemporaryTag());
  return name;
}

bool IsTemporaryName(const std::string& name) {
  return ParseTemporary(name).kind != TemporaryKind::kNone;
}

std::vector<std::string> RemoveStaleTemporaries(const std::string& folder) {
  std::vector<std::string> removed;
  std::error_code ec;
  const std::string key = fs::absolute(folder, ec).lexically_normal().string();
  {
    static std::mutex mutex;
    static std::set<std::string> done;
    std::lock_guard<std::mutex> lock(mutex);
    if (!done.insert(key).second) return removed;
  }
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    const ParsedTemporary t = ParseTemporary(name);
    if (t.kind == TemporaryKind::kNone || !ProcessIsGone(t.pid)) continue;
    std::error_code e2;
    const fs::path target = entry.path().parent_path() / t.base;
    if (t.kind == TemporaryKind::kBackup && !fs::exists(fs::symlink_status(target, e2))) {
      fs::rename(entry.path(), target, e2);
      if (!e2) {
        LogWarning("restored {} from the backup {} of a swap that process {} did not finish",
                   target.string(), name, t.pid);
        removed.push_back(entry.path().string());
      }
      continue;
    }
    fs::remove_all(entry.path(), e2);
    if (!e2) {
      LogDebug("removed {}, a temporary of process {} that no longer runs", entry.path().string(),
               t.pid);
      removed.push_back(entry.path().string());
    }
  }
  return removed;
}

std::vector<std::string> RemoveStaleSystemTemporaries() {
  std::vector<std::string> removed;
  static std::once_flag once;
  std::call_once(once, [&] {
    std::error_code ec;
    fs::path folder = fs::temp_directory_path(ec);
    if (ec) folder = "/tmp";
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
      const std::string name = entry.path().filename().string();
      const long pid = TemporaryTagPid(name, "impactdic-");
      std::error_code e2;
      if (pid <= 0 || !entry.is_regular_file(e2) || !ProcessIsGone(pid)) continue;
      if (fs::remove(entry.path(), e2)) removed.push_back(entry.path().string());
    }
  });
  return removed;
}

OutputGeneration::OutputGeneration(const std::string& folder, OutputGenerationOptions options)
    : folder_(folder), options_(std::move(options)) {
  if (folder.empty())
    throw Error(ErrorKind::kInvalidValue, "output folder", "an empty path", "a folder");
  std::error_code ec;
  fs::path dest = fs::absolute(folder, ec).lexically_normal();
  if (dest.filename().empty()) dest = dest.parent_path();
  // A link to a folder: the folder it names gets the new generation; the link stays.
  if (fs::is_symlink(fs::symlink_status(dest, ec))) dest = fs::weakly_canonical(dest, ec);
  if (dest == dest.root_path() || dest.filename() == "..") {
    throw Error(ErrorKind::kInvalidValue, "output folder", dest.string(),
                "a folder below the file system root, named without '..'")
        .WithFile(folder);
  }
  if (fs::exists(dest, ec) && !fs::is_directory(dest, ec)) {
    throw Error(ErrorKind::kInvalidValue, "output folder", "a file",
                "a folder (or a name that does not exist yet)")
        .WithFile(folder);
  }
  destination_ = dest.string();
  const fs::path parent = dest.parent_path();
  // After a signal, a generation nested in a staging folder the cleanup is removing (a campaign
  // test's results/) must not make that folder again: wait for the exit instead.
  MakeFolders(parent.string(), ec);
  if (ec || !fs::is_directory(parent)) {
    throw Error(ErrorKind::kIo, "output folder",
                "cannot create " + parent.string() + ": " +
                    (ec ? ec.message() : std::string("not a folder")),
                "a folder that can be created")
        .WithFile(folder);
  }
  if (access(parent.c_str(), W_OK) != 0) {
    throw Error(ErrorKind::kIo, "output folder", parent.string() + " is not writable",
                "a writable parent folder (the new outputs are made beside the output folder and "
                "renamed)")
        .WithFile(folder);
  }
  RemoveStaleTemporaries(parent.string());
  RemoveStaleSystemTemporaries();
  if (fs::is_directory(dest, ec)) {
    const std::vector<std::string> foreign = ForeignEntries();
    if (!foreign.empty()) {
      throw Error(ErrorKind::kInvalidValue, "output folder",
                  fmt::format("{} entr{} impactdic did not write: {}", foreign.size(),
                              foreign.size() == 1 ? "y" : "ies", Quoted(foreign, 5)),
                  "a new or empty folder, or one impactdic wrote (its " +
                      std::string(kOutputMarkerName) +
                      " lists what it may replace); move those entries or choose another folder")
          .WithFile(folder);
    }
  }
  staging_ = (parent / TemporaryName(dest.filename().string(), ".tmp-")).string();
  {
    // Registered and made as one step for a signal's cleanup, which waits for this block: it
    // removes the staging folder, or (signal before the block) the folder is never made. Without
    // the block a cleanup running between the two left it behind.
    const DeferInterrupts creating;
    if (!Interrupted()) {
      staging_guard_.emplace(staging_, creating);
      fs::create_directory(staging_, ec);
    }
  }
  WaitIfInterrupted();
  if (ec) {
    throw Error(ErrorKind::kIo, "output folder", "cannot make " + staging_ + ": " + ec.message(),
                "a writable folder")
        .WithFile(folder);
  }
  if (fs::is_directory(dest, ec)) fs::permissions(staging_, fs::status(dest, ec).permissions(), ec);
  const std::lock_guard<std::mutex> lock(staged_mutex);
  staged_folders.emplace_back(staging_, folder_);
}

OutputGeneration::~OutputGeneration() {
  {
    const std::lock_guard<std::mutex> lock(staged_mutex);
    std::erase_if(staged_folders, [&](const auto& s) { return s.first == staging_; });
  }
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

std::string OutputGeneration::Path(const std::string& name) const {
  return (fs::path(staging_) / name).string();
}

std::string OutputPathForMessages(std::string path) {
  const std::lock_guard<std::mutex> lock(staged_mutex);
  // Innermost first: a scene's generation inside a campaign's staging folder.
  for (std::size_t depth = 0; depth <= staged_folders.size(); ++depth) {
    const std::pair<std::string, std::string>* best = nullptr;
    for (const auto& s : staged_folders)
      if (IsSameOrInside(path, s.first) && (!best || s.first.size() > best->first.size()))
        best = &s;
    if (!best) break;
    path = path.size() == best->first.size()
               ? best->second
               : (fs::path(best->second) / path.substr(best->first.size() + 1)).string();
  }
  return path;
}

std::string OutputGeneration::FinalPath(const std::string& path) const {
  if (path == staging_) return folder_;
  if (IsSameOrInside(path, staging_))
    return (fs::path(folder_) / path.substr(staging_.size() + 1)).string();
  return path;
}

std::vector<std::string> OutputGeneration::ForeignEntries() const {
  const fs::path dest(destination_);
  const std::set<std::string> listed = ReadMarker(dest);
  std::vector<std::string> foreign;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dest, ec)) {
    const std::string name = entry.path().filename().string();
    std::error_code e2;
    if (name == kOutputMarkerName || listed.count(name) > 0 || Contains(options_.own_names, name) ||
        Contains(options_.known_names, name) || IsTemporaryName(name) ||
        (entry.is_directory(e2) && fs::exists(entry.path() / kOutputMarkerName, e2))) {
      continue;
    }
    foreign.push_back(name);
  }
  if (ec) {
    throw Error(ErrorKind::kIo, "output folder", "cannot list it: " + ec.message(),
                "a readable folder")
        .WithFile(folder_);
  }
  std::sort(foreign.begin(), foreign.end());
  return foreign;
}

void OutputGeneration::CarryOverPrevious() const {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(destination_, ec)) {
    const std::string name = entry.path().filename().string();
    std::error_code e2;
    if (name == kOutputMarkerName || IsTemporaryName(name) || Contains(options_.own_names, name) ||
        fs::exists(fs::symlink_status(fs::path(staging_) / name, e2))) {
      continue;
    }
    LinkTree(entry.path(), fs::path(staging_) / name);
  }
}

void OutputGeneration::WriteMarker() const {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(staging_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name != kOutputMarkerName && !IsTemporaryName(name)) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  std::string text = "# impactdic output folder, written by `" + options_.command + "` on " +
                     UtcNow() +
                     ".\n# Its entries are one generation: impactdic replaces them together "
                     "(and only them).\n";
  for (const auto& n : names) text += n + "\n";
  WriteTextFileAtomic(Path(kOutputMarkerName), text);
}

void OutputGeneration::SwapIn(bool had_previous) {
  if (!had_previous) {
    // rename() also replaces an empty folder that appeared meanwhile.
    if (std::rename(staging_.c_str(), destination_.c_str()) != 0)
      SwapError(folder_, std::strerror(errno));
    staging_guard_->Release();
    return;
  }
  if (options_.atomic_exchange && ExchangePaths(staging_, destination_)) {
    return;  // The staging name now holds the previous generation (removed by Commit).
  }
  if (options_.atomic_exchange && errno != EINVAL && errno != ENOSYS && errno != EOPNOTSUPP)
    SwapError(folder_, std::strerror(errno));
  // Two renames with a backup (a SIGKILL between them: RemoveStaleTemporaries restores it).
  const fs::path dest(destination_);
  const std::string backup =
      (dest.parent_path() / TemporaryName(dest.filename().string(), ".bak-")).string();
  if (std::rename(destination_.c_str(), backup.c_str()) != 0)
    SwapError(folder_, std::strerror(errno));
  if (std::rename(staging_.c_str(), destination_.c_str()) != 0) {
    const int error = errno;
    std::rename(backup.c_str(), destination_.c_str());
    SwapError(folder_, std::strerror(error));
  }
  // The staging name is free now: move the backup there, so that the registration (and the
  // destructor's path) cover it.
  if (std::rename(backup.c_str(), staging_.c_str()) != 0) {
    std::error_code ec;
    fs::remove_all(backup, ec);
  }
}

void OutputGeneration::Commit() {
  if (committed_) return;
  std::error_code ec;
  const bool had_previous = fs::is_directory(destination_, ec);
  // A shell whose current folder is the destination (or inside it) keeps seeing the removed
  // previous generation until it changes folder again.
  const std::string cwd = fs::current_path(ec).string();
  const bool replaces_cwd = had_previous && !ec && IsSameOrInside(cwd, destination_);
  if (had_previous && options_.keep_other_entries) CarryOverPrevious();
  WriteMarker();
  {
    DeferInterrupts swap;  // No registration may happen in here (it could wait for the exit).
    if (had_previous) {
      const std::vector<std::string> foreign = ForeignEntries();
      if (!foreign.empty()) {
        SwapError(folder_, fmt::format("{} appeared in it during the run", Quoted(foreign, 5)));
      }
    }
    SwapIn(had_previous);
    NoteOutputsComplete(folder_);
  }
  committed_ = true;
  // The previous generation, if any, is under the staging name.
  fs::remove_all(staging_, ec);
  staging_guard_->Release();
  if (replaces_cwd) {
    LogWarning(
        "{} was replaced by its new outputs; a shell inside it still sees the old, removed "
        "folder: run `cd {}` there",
        folder_, destination_);
  }
}

}  // namespace impactdic
