#include "impactdic/io/output_generation.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
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

constexpr std::string_view kLockSuffix = ".lock";
constexpr std::string_view kKindLine = "# kind: ";

// ".<name>.lock", <name> not empty: an output folder's lock file (OutputLockPath).
bool IsLockName(const std::string& name) {
  return name.size() > 1 + kLockSuffix.size() && name[0] == '.' &&
         std::string_view(name).substr(name.size() - kLockSuffix.size()) == kLockSuffix;
}

// "'a', 'b' and 3 more" of the folder's entries, without the marker and temporaries.
std::string SomeEntries(const fs::path& folder) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name != kOutputMarkerName && !IsTemporaryName(name)) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return Quoted(names, 4);
}

// "a run folder, written by `impactdic run` on 2026-11-27T10:00:00Z"
std::string WrittenBy(const OutputMarker& m) {
  return "a " + (m.kind.empty() ? std::string("impactdic") : m.kind) + " folder, written by `" +
         (m.command.empty() ? std::string("impactdic") : m.command) + "`" +
         (m.written_utc.empty() ? "" : " on " + m.written_utc);
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
  return ParseTemporary(name).kind != TemporaryKind::kNone || IsLockName(name);
}

std::string KindOfCommand(const std::string& command) {
  constexpr std::string_view kPrefix = "impactdic ";
  if (command.rfind(kPrefix, 0) != 0) return command;
  const std::string rest = command.substr(kPrefix.size());
  std::string word = rest.substr(0, rest.find(' '));
  if (rest.find("(test ") != std::string::npos) word += " test";
  return word;
}

OutputMarker ReadOutputMarker(const std::string& folder) {
  OutputMarker m;
  std::ifstream in(fs::path(folder) / kOutputMarkerName);
  m.present = static_cast<bool>(in);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(kKindLine, 0) == 0) {
      m.kind = line.substr(kKindLine.size());
    } else if (const std::size_t by = line.find("written by `");
               line.rfind('#', 0) == 0 && by != std::string::npos && m.command.empty()) {
      const std::size_t start = by + 12, end = line.find('`', start);
      if (end == std::string::npos) continue;
      m.command = line.substr(start, end - start);
      const std::size_t on = line.find(" on ", end);
      if (on != std::string::npos) {
        m.written_utc = line.substr(on + 4);
        if (!m.written_utc.empty() && m.written_utc.back() == '.') m.written_utc.pop_back();
      }
    } else if (!line.empty() && line[0] != '#') {
      m.entries.push_back(line);
    }
  }
  if (m.kind.empty() && !m.command.empty()) m.kind = KindOfCommand(m.command);
  return m;
}

void CheckOutputFolderName(const std::string& path, const std::string& option) {
  if (path.empty()) {
    throw Error(ErrorKind::kInvalidValue, option, "an empty name",
                "an output folder (leave the option out for the default)");
  }
  // ".<name>.tmp-<pid: at most 7 digits>-<16 hex digits>" beside the folder.
  constexpr std::size_t kStagingExtra = 1 + 5 + 7 + 1 + 16;
  const fs::path p = fs::path(path).lexically_normal();
  fs::path last = p.filename();
  if (last.empty()) last = p.parent_path().filename();
  for (const auto& part : p) {
    const std::size_t limit = part == last ? NAME_MAX - kStagingExtra : NAME_MAX;
    if (part.string().size() <= limit) continue;
    throw Error(ErrorKind::kInvalidValue, option,
                fmt::format("a name of {} bytes ('{}...')", part.string().size(),
                            part.string().substr(0, 24)),
                part == last ? fmt::format("an output folder name of at most {} bytes (the file "
                                           "system allows {}; impactdic stages the outputs "
                                           "beside it as .NAME.tmp-<pid>-<hex>)",
                                           limit, NAME_MAX)
                             : fmt::format("folder names of at most {} bytes (NAME_MAX)", limit));
  }
}

void CheckNotInAGeneration(const std::string& path, const std::string& option) {
  const fs::path folder = fs::absolute(path).parent_path();
  std::error_code ec;
  const bool summary = fs::exists(folder / "summary.json", ec);
  if (!summary && !fs::exists(folder / kOutputMarkerName, ec)) return;
  throw Error(ErrorKind::kInvalidValue, option,
              path + ", in a folder of outputs written together by impactdic (" +
                  (summary ? "with its summary.json" : "one generation") +
                  "): writing one file of it alone would leave the other files describing another "
                  "analysis",
              "a file of its own for this analysis (--output NEW.h5 outside that folder), or "
              "`impactdic run` to redo the whole folder");
}

std::string OutputLockPath(const std::string& folder) {
  fs::path dest = fs::path(folder).lexically_normal();
  if (dest.filename().empty()) dest = dest.parent_path();
  std::string name = ".";  // (Appended: GCC 12 warns wrongly on "." + ...)
  name.append(dest.filename().string()).append(kLockSuffix);
  return (dest.parent_path() / name).string();
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

OutputFolderLock::OutputFolderLock(const std::string& folder, const std::string& command)
    : path_(OutputLockPath(folder)) {
  for (int attempt = 0; attempt < 1000; ++attempt) {
    // Registered, made and locked as one step for a signal's cleanup (which waits for the block):
    // a signal between making the file and registering it left the lock file behind.
    const DeferInterrupts making;
    if (Interrupted()) break;
    guard_.emplace(path_, making);
    const int fd = open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
      guard_.reset();
      throw Error(ErrorKind::kIo, "output folder",
                  "cannot make its lock file " + path_ + ": " + std::strerror(errno),
                  "a writable parent folder")
          .WithFile(folder);
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      char text[256] = {};
      const ssize_t n = pread(fd, text, sizeof text - 1, 0);
      close(fd);
      guard_.reset();  // Another writer's (or a file system without flock): never removed by us.
      if (error != EWOULDBLOCK) {  // A file system without flock (some network ones).
        LogWarning(
            "{}: cannot lock {} ({}); two commands writing this folder at once are not "
            "detected",
            folder, path_, std::strerror(error));
        return;
      }
      std::string holder(text, n > 0 ? static_cast<std::size_t>(n) : 0);
      while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
      throw Error(ErrorKind::kIo, "output folder",
                  "being written by another command: " +
                      (holder.empty() ? std::string("a process that is starting") : holder) +
                      " (lock " + path_ + ")",
                  "one command writing a folder at a time: wait until it has finished, or choose "
                  "another output folder")
          .WithFile(folder);
    }
    struct stat by_fd {};
    struct stat by_path {};
    if (fstat(fd, &by_fd) == 0 && stat(path_.c_str(), &by_path) == 0 &&
        by_fd.st_ino == by_path.st_ino && by_fd.st_dev == by_path.st_dev) {
      fd_ = fd;
      const std::string text = fmt::format("process {} (`{}`, since {})\n",
                                           static_cast<long>(getpid()), command, UtcNow());
      if (ftruncate(fd, 0) == 0) {
        [[maybe_unused]] const ssize_t written = pwrite(fd, text.data(), text.size(), 0);
      }
      return;
    }
    close(fd);  // Its holder removed it meanwhile: lock the one that replaced it.
    guard_.reset();
  }
  WaitIfInterrupted();
  throw Error(ErrorKind::kIo, "output folder", "cannot lock " + path_,
              "a lock file that stays in place")
      .WithFile(folder);
}

OutputFolderLock::~OutputFolderLock() {
  if (fd_ < 0) return;
  // Removed while held: a writer that opened it meanwhile sees it gone and locks a new one.
  unlink(path_.c_str());
  close(fd_);
}

OutputGeneration::OutputGeneration(const std::string& folder, OutputGenerationOptions options)
    : folder_(folder), options_(std::move(options)) {
  CheckOutputFolderName(folder, "output folder");
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
  lock_.emplace(destination_, options_.command);
  RemoveStaleTemporaries(parent.string());
  RemoveStaleSystemTemporaries();
  kind_ = OwnKind();
  if (fs::is_directory(dest, ec)) CheckReplaceable();
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
  if (!committed_ && !staging_.empty()) {
    std::error_code ec;
    fs::remove_all(staging_, ec);
  }
}

std::string OutputGeneration::OwnKind() const {
  return options_.kind.empty() ? KindOfCommand(options_.command) : options_.kind;
}

void OutputGeneration::CheckReplaceable() {
  const std::vector<std::string> foreign = ForeignEntries();
  if (!foreign.empty()) {
    throw Error(ErrorKind::kInvalidValue, "output folder",
                fmt::format("{} entr{} impactdic did not write: {}", foreign.size(),
                            foreign.size() == 1 ? "y" : "ies", Quoted(foreign, 5)),
                "a new or empty folder, or one impactdic wrote (its " +
                    std::string(kOutputMarkerName) +
                    " lists what it may replace); move those entries or choose another folder")
        .WithFile(folder_);
  }
  const OutputMarker marker = ReadOutputMarker(destination_);
  if (marker.present && options_.keep_other_entries &&
      Contains(options_.replaces_kinds, marker.kind)) {
    kind_ = marker.kind;  // Render into a run's folder: still a run's folder.
  }
  // A folder of another kind replaced by --force: nothing of it is kept.
  if (marker.present && !marker.kind.empty() && marker.kind != kind_ &&
      !Contains(options_.replaces_kinds, marker.kind)) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(destination_, ec))
      dropped_entries_.push_back(entry.path().filename().string());
  }
  if (!options_.force) CheckKinds(marker);
  CheckRemovable();
  if (!marker.present) WarnOfUnmarkedEntries();
}

void OutputGeneration::WarnOfUnmarkedEntries() const {
  // Entries replaced although no marker says impactdic wrote them: named, never silently.
  std::vector<std::string> replaced;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(destination_, ec)) {
    const std::string name = entry.path().filename().string();
    std::error_code e2;
    if (IsTemporaryName(name) ||
        (entry.is_directory(e2) && fs::exists(entry.path() / kOutputMarkerName, e2)) ||
        (options_.keep_other_entries && !Contains(options_.own_names, name))) {
      continue;
    }
    replaced.push_back(name);
  }
  if (replaced.empty()) return;
  std::sort(replaced.begin(), replaced.end());
  LogWarning(
      "{} has no {} (an impactdic older than 2026-11-25 wrote it, or files are named like its "
      "outputs): {} taken for impactdic's outputs and replaced",
      folder_, kOutputMarkerName, Quoted(replaced, 5));
}

void OutputGeneration::CheckKinds(const OutputMarker& marker) const {
  std::string kinds = OwnKind();
  for (const std::string& k : options_.replaces_kinds) kinds += " or " + k;
  const std::string expected = fmt::format(
      "a new or empty folder, or a {} folder (what `{}` replaces); --force replaces it anyway",
      kinds, options_.command);
  if (marker.present && !marker.kind.empty() && marker.kind != kind_ &&
      !Contains(options_.replaces_kinds, marker.kind)) {
    throw Error(ErrorKind::kInvalidValue, "output folder",
                fmt::format("{}: {}", WrittenBy(marker), SomeEntries(destination_)), expected)
        .WithFile(folder_);
  }
  // Generations nested in it that are not part of it (results/t10 under `run -o results`).
  std::vector<std::string> nested;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(destination_, ec)) {
    const std::string name = entry.path().filename().string();
    std::error_code e2;
    if (!entry.is_directory(e2) || !fs::exists(entry.path() / kOutputMarkerName, e2) ||
        Contains(marker.entries, name) || Contains(options_.own_names, name) ||
        Contains(options_.known_names, name)) {
      continue;
    }
    const OutputMarker inner = ReadOutputMarker(entry.path().string());
    if (Contains(options_.nested_kinds, inner.kind)) continue;
    nested.push_back(fmt::format("'{}' ({})", name, WrittenBy(inner)));
  }
  if (nested.empty()) return;
  std::sort(nested.begin(), nested.end());
  std::string listed;
  for (std::size_t i = 0; i < nested.size() && i < 4; ++i) listed += (i ? ", " : "") + nested[i];
  if (nested.size() > 4) listed += fmt::format(" and {} more", nested.size() - 4);
  throw Error(ErrorKind::kInvalidValue, "output folder",
              fmt::format("a folder holding the outputs of other commands: {}", listed), expected)
      .WithFile(folder_);
}

void OutputGeneration::CheckRemovable() const {
  // Replacing the folder removes the previous generation: every folder in it must let us remove
  // its entries, else the swap would leave it behind under a hidden name.
  std::error_code ec;
  std::vector<std::string> locked;
  // A folder with entries needs write permission for them to be removed (an empty one goes with
  // its parent's).
  const auto removable = [](const fs::path& dir) {
    std::error_code e2;
    return fs::is_empty(dir, e2) || access(dir.c_str(), W_OK | X_OK) == 0;
  };
  if (!removable(destination_)) locked.push_back(folder_);
  for (auto it = fs::recursive_directory_iterator(destination_, ec);
       !ec && it != fs::recursive_directory_iterator() && locked.size() < 3; it.increment(ec)) {
    std::error_code e2;
    if (it->is_symlink(e2) || !it->is_directory(e2) || removable(it->path())) continue;
    locked.push_back((fs::path(folder_) / fs::relative(it->path(), destination_, e2)).string());
  }
  if (ec) locked.push_back(folder_ + " (" + ec.message() + ")");
  if (locked.empty()) return;
  throw Error(
      ErrorKind::kIo, "output folder",
      fmt::format("cannot replace it: you may not remove the entries of {}", Quoted(locked, 3)),
      "a folder whose earlier outputs you may remove (check the owner and permissions), "
      "or another output folder")
      .WithFile(folder_);
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
  const std::vector<std::string> listed = ReadOutputMarker(destination_).entries;
  std::vector<std::string> foreign;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dest, ec)) {
    const std::string name = entry.path().filename().string();
    std::error_code e2;
    if (name == kOutputMarkerName || Contains(listed, name) || Contains(options_.own_names, name) ||
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
        Contains(dropped_entries_, name) ||
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
                     UtcNow() + ".\n" + std::string(kKindLine) + kind_ +
                     "\n# Its entries are one generation: impactdic replaces them together "
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
  if (ec) {
    LogWarning(
        "{} holds its new outputs, but its previous ones could not all be removed ({}): they are "
        "left in {}; remove that folder by hand",
        folder_, ec.message(), staging_);
  }
  staging_guard_->Release();
  if (replaces_cwd) {
    LogWarning(
        "{} was replaced by its new outputs; a shell inside it still sees the old, removed "
        "folder: run `cd {}` there",
        folder_, destination_);
  }
}

}  // namespace impactdic
