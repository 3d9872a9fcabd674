// Test helper: a small tmpfs mounted for one test, to run writers into a full disk.
//
//   std::string why_not;
//   auto disk = SmallDisk::Mount(2 << 20, &why_not);
//   if (!disk) GTEST_SKIP() << "disk-full test skipped: " << why_not;
//   disk->LeaveFree(0);                     // a filler file takes every block
//   RunCli("model ... -o " + disk->File("x.h5"));
//
// Mounting needs root (CAP_SYS_ADMIN); Mount() says why it could not.
#ifndef IMPACTDIC_TESTS_RELIABILITY_SMALL_DISK_H_
#define IMPACTDIC_TESTS_RELIABILITY_SMALL_DISK_H_

#include <sys/mount.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace impactdic {

class SmallDisk {
 public:
  // Page size of tmpfs: its unit of allocation.
  static constexpr std::size_t kPage = 4096;

  static std::unique_ptr<SmallDisk> Mount(std::size_t size_bytes, std::string* why_not) {
    if (geteuid() != 0) {
      *why_not = "mounting a tmpfs needs root (this process is not root)";
      return nullptr;
    }
    static int counter = 0;
    const std::filesystem::path path =
        std::filesystem::temp_directory_path() /
        ("impactdic_small_disk_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    const std::string options = "size=" + std::to_string(size_bytes) + ",mode=0755";
    if (mount("tmpfs", path.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) != 0) {
      *why_not = std::string("mount -t tmpfs failed: ") + std::strerror(errno);
      std::filesystem::remove_all(path);
      return nullptr;
    }
    return std::unique_ptr<SmallDisk>(new SmallDisk(path));
  }

  ~SmallDisk() {
    umount2(path_.c_str(), MNT_DETACH);
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;

  std::string File(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

  std::size_t FreeBytes() const {
    struct statvfs info {};
    statvfs(path_.c_str(), &info);
    return static_cast<std::size_t>(info.f_bfree) * info.f_frsize;
  }

  // Writes (or rewrites) a filler file so that `free_bytes` (rounded down to whole pages) stay
  // free; false if there is less than that.
  bool LeaveFree(std::size_t free_bytes) {
    const std::filesystem::path filler = path_ / "filler";
    std::error_code ec;
    std::filesystem::remove(filler, ec);
    const std::size_t free_now = FreeBytes();
    free_bytes -= free_bytes % kPage;
    if (free_now < free_bytes) return false;
    std::ofstream out(filler, std::ios::binary);
    const std::vector<char> zeros(kPage, 0);
    for (std::size_t n = (free_now - free_bytes) / kPage; n > 0; --n)
      out.write(zeros.data(), kPage);
    out.close();
    return FreeBytes() == free_bytes;
  }

  // Every file under the disk whose name marks a temporary (".tmp-", as AtomicFile and the
  // renderers name theirs).
  std::vector<std::string> TemporaryFiles() const {
    std::vector<std::string> found;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(path_))
      if (entry.path().filename().string().find(".tmp-") != std::string::npos)
        found.push_back(entry.path().string());
    return found;
  }

  // Every regular file under the disk except the filler.
  std::vector<std::string> Files() const {
    std::vector<std::string> found;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(path_))
      if (entry.is_regular_file() && entry.path() != path_ / "filler")
        found.push_back(entry.path().string());
    return found;
  }

  // Bytes a file of `size` bytes takes on the disk.
  static std::size_t Pages(std::size_t size) { return (size + kPage - 1) / kPage * kPage; }

 private:
  explicit SmallDisk(std::filesystem::path path) : path_(std::move(path)) {}
  std::filesystem::path path_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_RELIABILITY_SMALL_DISK_H_
