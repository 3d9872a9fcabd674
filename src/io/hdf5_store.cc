#include "impactdic/io/hdf5_store.h"

#include <H5Cpp.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <tbb/task_group.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <system_error>

#include "impactdic/core/error.h"
#include "impactdic/core/version.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/input_file.h"
#include "impactdic/io/output_generation.h"

namespace impactdic {
namespace {

// Datasets at least this large are chunked and deflate-compressed, at zlib's fastest level: after
// the shuffle filter the values compress nearly as well as at level 4 (the benchmark pair's
// results: 620 kB against 608 kB), and the pair's whole correlate ran 1.9 % faster
// (docs/dic_speed.md).
constexpr std::size_t kCompressThreshold = 4096;
constexpr int kDeflateLevel = 1;
// Values of datasets whose chunks are filtered on workers before the writer writes them.
constexpr std::size_t kMaxDeferredBytes = std::size_t{16} << 20;

std::vector<std::string> SplitPath(const std::string& path) {
  std::vector<std::string> parts;
  std::string part;
  for (char c : path) {
    if (c == '/') {
      if (!part.empty()) parts.push_back(part);
      part.clear();
    } else {
      part += c;
    }
  }
  if (!part.empty()) parts.push_back(part);
  return parts;
}

std::string ParentOf(const std::string& path) {
  const auto parts = SplitPath(path);
  std::string parent;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) parent += "/" + parts[i];
  return parent.empty() ? "/" : parent;
}

std::string Normalise(const std::string& path) {
  std::string p;
  for (const auto& part : SplitPath(path)) p += "/" + part;
  return p.empty() ? "/" : p;
}

void WriteStringAttribute(H5::H5Object& object, const std::string& name, const std::string& value) {
  H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
  type.setCset(H5T_CSET_UTF8);
  if (object.attrExists(name)) object.removeAttr(name);
  H5::Attribute attr = object.createAttribute(name, type, H5::DataSpace(H5S_SCALAR));
  attr.write(type, value);
}

// Objects are created without HDF5's modification times (H5Pset_obj_track_times), so the same
// results give the same bytes whenever they are written; the file's own time is the root
// attribute `created_utc`.
H5::DSetCreatPropList UntimedDatasetProperties() {
  H5::DSetCreatPropList props;
  if (H5Pset_obj_track_times(props.getId(), false) < 0)
    throw H5::PropListIException("H5Pset_obj_track_times", "cannot stop tracking times");
  return props;
}

void CreateUntimedGroup(const H5::H5File& file, const std::string& path) {
  const hid_t properties = H5Pcreate(H5P_GROUP_CREATE);
  if (properties < 0) throw H5::PropListIException("H5Pcreate", "cannot make group properties");
  const herr_t untimed = H5Pset_obj_track_times(properties, false);
  const hid_t group =
      untimed < 0 ? -1
                  : H5Gcreate2(file.getId(), path.c_str(), H5P_DEFAULT, properties, H5P_DEFAULT);
  H5Pclose(properties);
  if (group < 0) throw H5::GroupIException("H5Gcreate2", "cannot create the group " + path);
  H5Gclose(group);
}

std::string UtcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

template <typename Fn>
auto Guard(const std::string& file, const std::string& what, Fn&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const H5::Exception& e) {
    throw Error(ErrorKind::kIo, what, e.getDetailMsg(), "a valid HDF5 operation")
        .WithFile(OutputPathForMessages(file));
  }
}

}  // namespace

// The file is built by HDF5's core driver (no backing store) and written to the disk by us, not
// by HDF5: in HDF5 1.10 a close whose final flush fails (a full disk) frees the file but leaves
// its id registered, and the next close of that id, or the library's own clean-up at exit, reads
// freed memory (an earlier segfault); the C++ objects' destructors also printed "H5Dclose
// failed" lines. Disk errors now come only from our own checked calls, as one Error naming the
// file.
constexpr std::size_t kCoreIncrement = std::size_t{4} << 20;  // growth step of the image [bytes]
// Backing::kFile: the file grows a page at a time (the disk holds what the file uses, so a file
// that fits on the disk can be written), and the pages written are returned to the page cache
// every kCoreIncrement of growth.
constexpr std::size_t kFileIncrement = 4096;

// A name no file has, for a file image held in memory.
std::string ImageName(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + " (in memory " + std::to_string(getpid()) + "-" + std::to_string(counter++) + ")";
}

// The core driver's buffer, allocated through file image callbacks (H5Pset_file_image_callbacks)
// so that Commit() writes the file from where the driver keeps it: H5Fget_file_image would copy
// it out first, holding the whole file in memory twice. The driver's own buffer (ops FILE_OPEN,
// FILE_RESIZE, FILE_CLOSE) is a mapping that grows by mremap without a copy, whatever the
// allocator's thresholds; the property lists' copies of an initial image (kUpdate) are plain
// allocations.
//  - Backing::kFile (fd >= 0): a shared mapping of the writer's temporary file in the output's
//    folder. Each growth first reserves the disk blocks (posix_fallocate: a full disk is known
//    there and then, never a SIGBUS or a failed write-back later) and then returns the pages
//    written so far to the page cache (MADV_DONTNEED keeps their data in the file), so the process
//    holds about one growth step of the file however large it gets; Commit() renames the file.
//    When the disk has no room the growth still succeeds, in an anonymous copy of the buffer
//    (`error` set): HDF5 must never see a failed allocation (a failed flush inside HDF5 1.10 ends
//    in the segfault above), so the operation completes in memory and ThrowIfNoRoom then throws
//    the disk's error; the file is never committed.
//  - Backing::kMemory (fd < 0): an anonymous mapping, freed when the file is closed.
struct CoreImage {
  void* data = nullptr;     // The file's bytes; null before the first write.
  std::size_t size = 0;     // Bytes the driver asked for (>= what the file uses).
  std::size_t mapped = 0;   // Bytes mapped (size rounded up to pages).
  int fd = -1;              // The temporary file under the mapping (Backing::kFile).
  std::size_t dropped = 0;  // `mapped` when the pages were last returned (Backing::kFile).
  int error = 0;            // The disk's error once it had no room (then anonymous, as kMemory).
  bool OnDisk() const { return fd >= 0 && error == 0; }
};

std::size_t PageRounded(std::size_t size) {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  return (std::max<std::size_t>(size, 1) + page - 1) / page * page;
}

bool IsDriverBuffer(H5FD_file_image_op_t op) {
  return op == H5FD_FILE_IMAGE_OP_FILE_OPEN || op == H5FD_FILE_IMAGE_OP_FILE_RESIZE ||
         op == H5FD_FILE_IMAGE_OP_FILE_CLOSE;
}

// Reserves the first `bytes` of the temporary file on the disk; false (image.error set) if the
// disk has no room.
bool Reserve(CoreImage& image, std::size_t bytes) {
  const int error = posix_fallocate(image.fd, 0, static_cast<off_t>(bytes));
  if (error == 0) return true;
  image.error = error;
  return false;
}

// After each operation of a writer: the disk's error once its file found no room (the operation
// itself completed in memory).
void ThrowIfNoRoom(const CoreImage& image, const std::string& file) {
  if (image.error != 0) throw WriteError(file, image.error);
}

void* MapAnonymous(std::size_t mapped) {
  return mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
}

void* ImageMalloc(std::size_t size, H5FD_file_image_op_t op, void* udata) {
  if (!IsDriverBuffer(op)) return std::malloc(size);
  auto* image = static_cast<CoreImage*>(udata);
  if (image->data) return nullptr;  // One driver buffer per writer.
  const std::size_t mapped = PageRounded(size);
  const bool on_disk = image->OnDisk() && Reserve(*image, mapped);
  void* p = on_disk ? mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_SHARED, image->fd, 0)
                    : MapAnonymous(mapped);
  if (p == MAP_FAILED) return nullptr;
  image->data = p;
  image->size = size;
  image->mapped = mapped;
  return p;
}

void* ImageMemcpy(void* dest, const void* src, std::size_t size, H5FD_file_image_op_t, void*) {
  return std::memcpy(dest, src, size);
}

void* ImageRealloc(void* ptr, std::size_t size, H5FD_file_image_op_t op, void* udata) {
  auto* image = static_cast<CoreImage*>(udata);
  if (!IsDriverBuffer(op)) return std::realloc(ptr, size);
  if (!ptr) return ImageMalloc(size, op, udata);
  if (ptr != image->data) return nullptr;
  const std::size_t mapped = PageRounded(size);
  if (image->OnDisk() && !Reserve(*image, mapped)) {
    // No room: the rest in memory (the buffer copied out of the file).
    void* copy = MapAnonymous(mapped);
    if (copy == MAP_FAILED) return nullptr;
    std::memcpy(copy, ptr, std::min(image->size, size));
    munmap(ptr, image->mapped);
    image->data = copy;
    image->size = size;
    image->mapped = mapped;
    return copy;
  }
  void* p = mremap(ptr, image->mapped, mapped, MREMAP_MAYMOVE);
  if (p == MAP_FAILED) return nullptr;
  // The pages written so far stay in the file (the page cache), not in the process.
  if (image->OnDisk() && mapped >= image->dropped + kCoreIncrement) {
    madvise(p, image->mapped, MADV_DONTNEED);
    image->dropped = mapped;
  }
  image->data = p;
  image->size = size;
  image->mapped = mapped;
  return p;
}

herr_t ImageFree(void* ptr, H5FD_file_image_op_t, void* udata) {
  auto* image = static_cast<CoreImage*>(udata);
  if (ptr && ptr == image->data) {
    munmap(ptr, image->mapped);
    image->data = nullptr;
    image->size = image->mapped = image->dropped = 0;
  } else {
    std::free(ptr);
  }
  return 0;
}

// What H5Fget_file_image does to its copy, done to the image itself before it is written: the
// superblock's file consistency flags (set while the file is open for writing) cleared, so the
// file on the disk is byte for byte the one H5Fget_file_image would give. The image is not used
// afterwards (the file is closed). Superblock versions 0 and 1 (what HDF5 writes by default; HDF5
// file format specification, "Superblock"): 4 bytes at offset 20. false for a superblock that is
// not at the start (a user block) or of a later version (whose flags are under a checksum): the
// image is then copied out by HDF5.
bool ClearStatusFlags(unsigned char* image, std::size_t size) {
  constexpr unsigned char kSignature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
  if (size < 24 || std::memcmp(image, kSignature, sizeof kSignature) != 0) return false;
  if (image[8] > 1) return false;
  std::memset(image + 20, 0, 4);
  return true;
}

// The property lists copy the callbacks' udata: all copies share the writer's CoreImage.
void* ImageUdataCopy(void* udata) { return udata; }
herr_t ImageUdataFree(void*) { return 0; }

void SetImageCallbacks(H5::FileAccPropList& access, CoreImage* image) {
  H5FD_file_image_callbacks_t callbacks = {ImageMalloc,    ImageMemcpy,    ImageRealloc, ImageFree,
                                           ImageUdataCopy, ImageUdataFree, image};
  if (H5Pset_file_image_callbacks(access.getId(), &callbacks) < 0)
    throw H5::PropListIException("H5Pset_file_image_callbacks", "cannot set the image callbacks");
}

namespace {

// The one chunk of a compressed dataset, filtered on a worker while the writer goes on (HDF5's
// serial library compresses a chunk only when the dataset is closed, one dataset after the other):
// the values in the file's byte layout, then shuffled and deflated as HDF5's shuffle and deflate
// filters do (byte k of every value together, then zlib's compress2 at kDeflateLevel), and
// written as the filtered chunk (H5Dwrite_chunk) when the writer flushes. Readers see the same
// dataset; the file's bytes are those HDF5 would write, in another order.
struct DeferredChunk {
  std::string path;
  int rank = 0;
  std::size_t element_size = 0;
  std::vector<unsigned char> raw;
  std::vector<unsigned char> filtered;  // Empty: not filtered (raw is written through HDF5).
};

void ShuffleDeflate(DeferredChunk* chunk) {
  try {
    const std::size_t size = chunk->element_size, n = chunk->raw.size() / size;
    std::vector<unsigned char> shuffled(chunk->raw.size());
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t b = 0; b < size; ++b) shuffled[b * n + i] = chunk->raw[i * size + b];
    uLongf bytes = compressBound(static_cast<uLong>(shuffled.size()));
    std::vector<unsigned char> out(bytes);
    if (compress2(out.data(), &bytes, shuffled.data(), static_cast<uLong>(shuffled.size()),
                  kDeflateLevel) != Z_OK)
      return;
    out.resize(bytes);
    chunk->filtered = std::move(out);
  } catch (const std::bad_alloc&) {  // Left to HDF5's own filters.
  }
}

}  // namespace

struct H5Writer::Impl {
  std::string final_path;
  std::optional<AtomicFile>
      spill;        // Backing::kFile: the temporary file (image.fd) renamed on Commit.
  CoreImage image;  // Before `file`: the file is closed (and its image freed) first.
  H5::H5File file;
  bool open = false;
  // Chunks being filtered (DeferredChunk), written by Flush in the order of their datasets.
  std::vector<std::unique_ptr<DeferredChunk>> deferred;
  tbb::task_group filtering;

  std::size_t deferred_bytes = 0;

  // At most kMaxDeferredBytes of values wait (then they are written): the writer's memory stays
  // bounded whatever the number of datasets.
  void Defer(std::unique_ptr<DeferredChunk> chunk) {
    DeferredChunk* c = chunk.get();
    deferred_bytes += c->raw.size();
    deferred.push_back(std::move(chunk));
    filtering.run([c] { ShuffleDeflate(c); });
    if (deferred_bytes > kMaxDeferredBytes) Flush();
  }
  bool Deferred(const std::string& path) const {
    return std::any_of(deferred.begin(), deferred.end(),
                       [&path](const auto& c) { return c->path == path; });
  }
  // Writes the deferred chunks into their datasets.
  void Flush() {
    filtering.wait();
    for (const auto& c : deferred) {
      Guard(final_path, "dataset " + c->path, [&] {
        H5::DataSet ds = file.openDataSet(c->path);
        if (c->filtered.empty()) {
          ds.write(c->raw.data(), ds.getDataType());  // The memory layout is the file's.
          return;
        }
        const std::array<hsize_t, 4> offset{};
        if (H5Dwrite_chunk(ds.getId(), H5P_DEFAULT, /*filters=*/0, offset.data(),
                           c->filtered.size(), c->filtered.data()) < 0)
          throw H5::DataSetIException("H5Dwrite_chunk", "cannot write the chunk");
      });
    }
    deferred.clear();
    deferred_bytes = 0;
    ThrowIfNoRoom(image, final_path);
  }

  // Closes the temporary file; its error number (0 = none). The file itself is kept.
  int CloseSpill() {
    if (image.fd < 0) return 0;
    const int error = close(image.fd) != 0 && errno != EINTR ? errno : 0;
    image.fd = -1;
    return error;
  }
};

H5Writer::H5Writer(const std::string& final_path) : H5Writer(final_path, Mode::kCreate) {}

H5Writer::H5Writer(const std::string& final_path, Mode mode, const std::string& source_path,
                   Backing backing)
    : impl_(std::make_unique<Impl>()) {
  H5::Exception::dontPrint();
  impl_->final_path = final_path;
  const std::string& source = source_path.empty() ? final_path : source_path;
  if (mode == Mode::kUpdate) {
    H5Reader check(source);  // Error if missing or not HDF5.
  }
  CheckOutputLocation(final_path);
  if (backing == Backing::kFile) {
    impl_->spill.emplace(final_path);
    impl_->image.fd =
        open(impl_->spill->temp_path().c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (impl_->image.fd < 0) throw WriteError(final_path, errno);
  }
  // kUpdate starts from the existing file's bytes: HDF5 never opens the original, so readers of
  // it (another process rendering it) are not locked out and it stays as it is until Commit().
  // No size limit: the file is one impactdic wrote (results.h5 with /frames may be gigabytes).
  std::string existing;
  if (mode == Mode::kUpdate)
    existing = ReadInputFile(source, "an HDF5 file", std::numeric_limits<std::uintmax_t>::max());
  Guard(final_path, "open", [&] {
    H5::FileAccPropList access;
    access.setCore(backing == Backing::kFile ? kFileIncrement : kCoreIncrement,
                   /*backing_store=*/false);
    SetImageCallbacks(access, &impl_->image);  // Before the initial image (HDF5's rule).
    if (mode == Mode::kUpdate &&
        H5Pset_file_image(access.getId(), existing.data(), existing.size()) < 0)
      throw H5::PropListIException("H5Pset_file_image", "cannot use the file's bytes");
    // An image must not be opened under the name of a file that exists (the core driver would
    // open that file instead); the name is only HDF5's, our messages name final_path.
    impl_->file = H5::H5File(mode == Mode::kUpdate ? ImageName(final_path) : final_path,
                             mode == Mode::kUpdate ? H5F_ACC_RDWR : H5F_ACC_TRUNC,
                             H5::FileCreatPropList::DEFAULT, access);
    impl_->open = true;
  });
  ThrowIfNoRoom(impl_->image, final_path);
}

namespace {

H5Writer::Mode ModeForExisting(const std::string& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec) ? H5Writer::Mode::kUpdate : H5Writer::Mode::kCreate;
}

}  // namespace

H5Writer::H5Writer(const std::string& final_path, const std::vector<std::string>& owned_groups)
    : H5Writer(final_path, ModeForExisting(final_path)) {
  for (const std::string& group : owned_groups) Remove(group);
}

void H5Writer::Remove(const std::string& path) {
  impl_->Flush();
  Guard(final_path(), "remove " + path, [&] {
    std::string current;
    for (const auto& part : SplitPath(path)) {
      current += "/" + part;
      if (!impl_->file.nameExists(current)) return;
    }
    if (current.empty()) return;
    impl_->file.unlink(current);
  });
  ThrowIfNoRoom(impl_->image, final_path());
}

// Closing the file cannot fail on the disk (HDF5 writes only to the driver's buffer); nothing is
// under the final name unless Commit() ran (the temporary file is removed).
H5Writer::~H5Writer() {
  impl_->filtering.wait();  // Chunks not flushed are dropped with the file.
  if (impl_->open) {
    try {
      impl_->file.close();
    } catch (const H5::Exception&) {
    }
  }
  impl_->CloseSpill();
}

const std::string& H5Writer::final_path() const { return impl_->final_path; }

void H5Writer::CreateGroup(const std::string& path) {
  Guard(final_path(), "group " + path, [&] {
    std::string current;
    for (const auto& part : SplitPath(path)) {
      current += "/" + part;
      if (!impl_->file.nameExists(current)) CreateUntimedGroup(impl_->file, current);
    }
  });
  ThrowIfNoRoom(impl_->image, final_path());
}

namespace {

// With `defer`, a dataset compressed as one chunk whose values have the file's layout in memory
// is handed to it (DeferredChunk) instead of written.
template <typename T>
void WriteDataset(H5::H5File& file, const std::string& file_name, const std::string& path,
                  const std::vector<T>& data, const Dims& dims, const H5::PredType& mem_type,
                  const H5::PredType& file_type, const std::string& units,
                  const std::string& description,
                  const std::function<void(std::unique_ptr<DeferredChunk>)>& defer = {}) {
  if (dims.empty() || dims.size() > 4) {
    throw Error(ErrorKind::kInvalidValue, "dataset " + path, std::to_string(dims.size()) + " dims",
                "1 to 4 dimensions");
  }
  const std::size_t count =
      std::accumulate(dims.begin(), dims.end(), std::size_t{1}, std::multiplies<>());
  if (count != data.size()) {
    throw Error(ErrorKind::kInvalidValue, "dataset " + path,
                std::to_string(data.size()) + " values",
                std::to_string(count) + " = product of dims");
  }
  std::vector<hsize_t> h_dims(dims.begin(), dims.end());
  H5::DataSpace space(static_cast<int>(h_dims.size()), h_dims.data());
  H5::DSetCreatPropList props = UntimedDatasetProperties();
  bool one_chunk = false;
  if (count >= kCompressThreshold) {
    // Chunks of whole trailing dimensions, about 64k elements each.
    std::vector<hsize_t> chunk = h_dims;
    std::size_t elements = count;
    for (std::size_t d = 0; d < chunk.size() && elements > 65536; ++d) {
      const std::size_t rest = elements / chunk[d];
      const hsize_t keep = std::max<hsize_t>(1, 65536 / std::max<std::size_t>(rest, 1));
      if (keep < chunk[d]) chunk[d] = keep;
      elements = rest * chunk[d];
    }
    props.setChunk(static_cast<int>(chunk.size()), chunk.data());
    props.setShuffle();
    props.setDeflate(kDeflateLevel);
    one_chunk = chunk == h_dims;
  }
  const bool deferred = defer && one_chunk && H5Tequal(mem_type.getId(), file_type.getId()) > 0;
  Guard(file_name, "dataset " + path, [&] {
    if (file.nameExists(path)) file.unlink(path);
    H5::DataSet ds = file.createDataSet(path, file_type, space, props);
    if (count > 0 && !deferred) ds.write(data.data(), mem_type);
    WriteStringAttribute(ds, "units", units);
    WriteStringAttribute(ds, "description", description);
  });
  if (deferred) {
    auto chunk = std::make_unique<DeferredChunk>();
    chunk->path = path;
    chunk->rank = static_cast<int>(dims.size());
    chunk->element_size = sizeof(T);
    chunk->raw.resize(count * sizeof(T));
    std::memcpy(chunk->raw.data(), data.data(), chunk->raw.size());
    defer(std::move(chunk));
  }
}

}  // namespace

void H5Writer::Write(const std::string& path, const std::vector<double>& data, const Dims& dims,
                     const std::string& units, const std::string& description) {
  const std::string name = Normalise(path);
  if (impl_->Deferred(name)) impl_->Flush();  // Replaced: its old chunk first.
  CreateGroup(ParentOf(path));
  WriteDataset(impl_->file, final_path(), name, data, dims, H5::PredType::NATIVE_DOUBLE,
               H5::PredType::IEEE_F64LE, units, description,
               [this](std::unique_ptr<DeferredChunk> c) { impl_->Defer(std::move(c)); });
  ThrowIfNoRoom(impl_->image, final_path());
}
void H5Writer::Write(const std::string& path, const std::vector<float>& data, const Dims& dims,
                     const std::string& units, const std::string& description) {
  const std::string name = Normalise(path);
  if (impl_->Deferred(name)) impl_->Flush();  // Replaced: its old chunk first.
  CreateGroup(ParentOf(path));
  WriteDataset(impl_->file, final_path(), name, data, dims, H5::PredType::NATIVE_FLOAT,
               H5::PredType::IEEE_F32LE, units, description,
               [this](std::unique_ptr<DeferredChunk> c) { impl_->Defer(std::move(c)); });
  ThrowIfNoRoom(impl_->image, final_path());
}
void H5Writer::Write(const std::string& path, const std::vector<std::int32_t>& data,
                     const Dims& dims, const std::string& units, const std::string& description) {
  const std::string name = Normalise(path);
  if (impl_->Deferred(name)) impl_->Flush();  // Replaced: its old chunk first.
  CreateGroup(ParentOf(path));
  WriteDataset(impl_->file, final_path(), name, data, dims, H5::PredType::NATIVE_INT32,
               H5::PredType::STD_I32LE, units, description,
               [this](std::unique_ptr<DeferredChunk> c) { impl_->Defer(std::move(c)); });
  ThrowIfNoRoom(impl_->image, final_path());
}
void H5Writer::Write(const std::string& path, const std::vector<std::uint8_t>& data,
                     const Dims& dims, const std::string& units, const std::string& description) {
  const std::string name = Normalise(path);
  if (impl_->Deferred(name)) impl_->Flush();  // Replaced: its old chunk first.
  CreateGroup(ParentOf(path));
  WriteDataset(impl_->file, final_path(), name, data, dims, H5::PredType::NATIVE_UINT8,
               H5::PredType::STD_U8LE, units, description,
               [this](std::unique_ptr<DeferredChunk> c) { impl_->Defer(std::move(c)); });
  ThrowIfNoRoom(impl_->image, final_path());
}
void H5Writer::Write(const std::string& path, const std::vector<std::uint16_t>& data,
                     const Dims& dims, const std::string& units, const std::string& description) {
  const std::string name = Normalise(path);
  if (impl_->Deferred(name)) impl_->Flush();  // Replaced: its old chunk first.
  CreateGroup(ParentOf(path));
  WriteDataset(impl_->file, final_path(), name, data, dims, H5::PredType::NATIVE_UINT16,
               H5::PredType::STD_U16LE, units, description,
               [this](std::unique_ptr<DeferredChunk> c) { impl_->Defer(std::move(c)); });
  ThrowIfNoRoom(impl_->image, final_path());
}
void H5Writer::WriteStack(const std::string& path, const Dims& dims, int bits,
                          const std::function<void(std::size_t, void*)>& fill,
                          const std::string& units, const std::string& description) {
  impl_->Flush();
  const std::string name = Normalise(path);
  if (dims.size() != 3 || (bits != 8 && bits != 16)) {
    throw Error(ErrorKind::kInvalidValue, "dataset " + name,
                std::to_string(dims.size()) + " dims, " + std::to_string(bits) + " bits",
                "[images x rows x cols] of 8 or 16 bits");
  }
  CreateGroup(ParentOf(path));
  const H5::PredType& mem_type =
      bits == 8 ? H5::PredType::NATIVE_UINT8 : H5::PredType::NATIVE_UINT16;
  const H5::PredType& file_type = bits == 8 ? H5::PredType::STD_U8LE : H5::PredType::STD_U16LE;
  const std::vector<hsize_t> h_dims(dims.begin(), dims.end());
  H5::DataSpace space(3, h_dims.data());
  H5::DSetCreatPropList props = UntimedDatasetProperties();
  const hsize_t chunk[3] = {1, std::max<hsize_t>(1, h_dims[1]), std::max<hsize_t>(1, h_dims[2])};
  const std::size_t per_image = dims[1] * dims[2];
  if (dims[0] > 0 && per_image > 0) {
    props.setChunk(3, chunk);
    props.setShuffle();
    props.setDeflate(kDeflateLevel);
  }
  std::vector<std::uint8_t> buffer(per_image * static_cast<std::size_t>(bits / 8));
  Guard(final_path(), "dataset " + name, [&] {
    if (impl_->file.nameExists(name)) impl_->file.unlink(name);
    H5::DataSet ds = impl_->file.createDataSet(name, file_type, space, props);
    const H5::DataSpace one(3, chunk);
    for (std::size_t f = 0; f < dims[0] && per_image > 0; ++f) {
      fill(f, buffer.data());
      const hsize_t start[3] = {f, 0, 0};
      H5::DataSpace slab = ds.getSpace();
      slab.selectHyperslab(H5S_SELECT_SET, chunk, start);
      ds.write(buffer.data(), mem_type, one, slab);
    }
    WriteStringAttribute(ds, "units", units);
    WriteStringAttribute(ds, "description", description);
  });
  ThrowIfNoRoom(impl_->image, final_path());
}

void H5Writer::Write(const std::string& path, const std::vector<double>& data,
                     const std::string& units, const std::string& description) {
  Write(path, data, Dims{data.size()}, units, description);
  ThrowIfNoRoom(impl_->image, final_path());
}

bool H5Writer::Exists(const std::string& path) const {
  const std::string p = Normalise(path);
  std::string current;
  for (const auto& part : SplitPath(p)) {
    current += "/" + part;
    if (!impl_->file.nameExists(current)) return false;
  }
  return true;
}

Dims H5Writer::Dimensions(const std::string& path) const {
  if (!Exists(path)) {
    throw Error(ErrorKind::kInvalidValue, "dataset " + path, "missing", "the dataset to exist");
  }
  return Guard(final_path(), "dataset " + path, [&] {
    H5::DataSpace space = impl_->file.openDataSet(Normalise(path)).getSpace();
    std::vector<hsize_t> h(space.getSimpleExtentNdims());
    space.getSimpleExtentDims(h.data());
    return Dims(h.begin(), h.end());
  });
}

namespace {

std::vector<std::string> GroupMembers(const H5::H5File& file, const std::string& file_name,
                                      const std::string& group_path) {
  return Guard(file_name, "group " + group_path, [&] {
    H5::Group g = file.openGroup(Normalise(group_path));
    std::vector<std::string> names;
    for (hsize_t i = 0; i < g.getNumObjs(); ++i) names.push_back(g.getObjnameByIdx(i));
    return names;
  });
}

}  // namespace

std::vector<std::string> H5Writer::List(const std::string& group_path) const {
  return GroupMembers(impl_->file, final_path(), group_path);
}

namespace {

// The selection of one view part in its source ([N], or row `row` of [F x N]), checked against
// the view's N; the error names the view and the source.
H5::DataSpace ViewSourceSelection(const H5::DataSet& source, const std::string& view,
                                  const H5Writer::ViewPart& part, std::size_t n) {
  H5::DataSpace space = source.getSpace();
  std::vector<hsize_t> dims(space.getSimpleExtentNdims());
  space.getSimpleExtentDims(dims.data());
  const bool by_row = part.row.has_value();
  const bool fits = by_row ? dims.size() == 2 && dims[1] == n && *part.row < dims[0]
                           : dims.size() == 1 && dims[0] == n;
  if (!fits) {
    throw Error(ErrorKind::kInvalidValue, "source " + part.source + " of view " + view,
                std::to_string(dims.size()) + "-D",
                by_row ? "[F x " + std::to_string(n) + "] with the row inside"
                       : "[" + std::to_string(n) + "]");
  }
  if (by_row) {
    const std::array<hsize_t, 2> start = {*part.row, 0};
    const std::array<hsize_t, 2> count = {1, n};
    space.selectHyperslab(H5S_SELECT_SET, count.data(), start.data());
  }
  return space;
}

}  // namespace

void H5Writer::WriteView(const std::string& path, const Dims& dims,
                         const std::vector<ViewPart>& parts, const std::string& units,
                         const std::string& description) {
  impl_->Flush();
  if (dims.empty() || dims.size() > 2 || parts.empty()) {
    throw Error(ErrorKind::kInvalidValue, "view " + path,
                std::to_string(dims.size()) + " dims, " + std::to_string(parts.size()) + " parts",
                "[N] or [N x C] with at least one part");
  }
  Guard(final_path(), "view " + path, [&] {
    const std::string p = Normalise(path);
    const std::vector<hsize_t> h_dims(dims.begin(), dims.end());
    H5::DataSpace view_space(static_cast<int>(h_dims.size()), h_dims.data());
    H5::DSetCreatPropList props = UntimedDatasetProperties();
    H5::DataType type;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const H5::DataSet source = impl_->file.openDataSet(Normalise(parts[i].source));
      if (i == 0) type = source.getDataType();
      const H5::DataSpace source_space = ViewSourceSelection(source, path, parts[i], dims[0]);
      if (dims.size() == 2 && parts[i].column >= dims[1]) {
        throw Error(ErrorKind::kInvalidValue, "column of " + parts[i].source + " in view " + path,
                    std::to_string(parts[i].column), "< " + std::to_string(dims[1]));
      }
      if (dims.size() == 2) {  // Column `column`; a 1-D view is all selected.
        const std::array<hsize_t, 2> start = {0, parts[i].column};
        const std::array<hsize_t, 2> count = {dims[0], 1};
        view_space.selectHyperslab(H5S_SELECT_SET, count.data(), start.data());
      }
      if (H5Pset_virtual(props.getId(), view_space.getId(), ".", Normalise(parts[i].source).c_str(),
                         source_space.getId()) < 0) {
        throw H5::PropListIException("H5Pset_virtual", "cannot map " + parts[i].source);
      }
    }
    view_space.selectAll();
    const std::string parent = ParentOf(p);
    if (!parent.empty() && parent != "/") CreateGroup(parent);
    if (impl_->file.nameExists(p)) impl_->file.unlink(p);
    H5::DataSet ds = impl_->file.createDataSet(p, type, view_space, props);
    WriteStringAttribute(ds, "units", units);
    WriteStringAttribute(ds, "description", description);
  });
  ThrowIfNoRoom(impl_->image, final_path());
}

void H5Writer::SetAttribute(const std::string& object_path, const std::string& name,
                            const std::string& value) {
  Guard(final_path(), "attribute " + name + " of " + object_path, [&] {
    const std::string path = Normalise(object_path);
    if (path == "/") {
      H5::Group root = impl_->file.openGroup("/");
      WriteStringAttribute(root, name, value);
      return;
    }
    if (!impl_->file.nameExists(path)) CreateGroup(path);
    if (impl_->file.childObjType(path) == H5O_TYPE_DATASET) {
      H5::DataSet ds = impl_->file.openDataSet(path);
      WriteStringAttribute(ds, name, value);
    } else {
      H5::Group g = impl_->file.openGroup(path);
      WriteStringAttribute(g, name, value);
    }
  });
  ThrowIfNoRoom(impl_->image, final_path());
}

void H5Writer::SetAttribute(const std::string& object_path, const std::string& name, double value) {
  Guard(final_path(), "attribute " + name + " of " + object_path, [&] {
    const std::string path = Normalise(object_path);
    if (path != "/" && !impl_->file.nameExists(path)) CreateGroup(path);
    auto write = [&](H5::H5Object& obj) {
      if (obj.attrExists(name)) obj.removeAttr(name);
      H5::Attribute attr =
          obj.createAttribute(name, H5::PredType::IEEE_F64LE, H5::DataSpace(H5S_SCALAR));
      attr.write(H5::PredType::NATIVE_DOUBLE, &value);
    };
    if (path != "/" && impl_->file.childObjType(path) == H5O_TYPE_DATASET) {
      H5::DataSet ds = impl_->file.openDataSet(path);
      write(ds);
    } else {
      H5::Group g = impl_->file.openGroup(path);
      write(g);
    }
  });
  ThrowIfNoRoom(impl_->image, final_path());
}

void H5Writer::WriteProvenance(const std::string& scene_yaml_text) {
  SetAttribute("/", "tool", "impactdic");
  SetAttribute("/", "tool_version", Version());
  SetAttribute("/", "git_revision", GitRevision());
  SetAttribute("/", "created_utc", UtcNow());
  CreateGroup("/provenance");
  SetAttribute("/provenance", "scene_yaml", scene_yaml_text);
  SetAttribute("/provenance", "tool_version", Version());
  SetAttribute("/provenance", "git_revision", GitRevision());
}

std::vector<char> H5Writer::CloseToImage() {
  impl_->Flush();
  std::vector<char> image;
  Guard(final_path(), "close", [&] {
    impl_->file.flush(H5F_SCOPE_GLOBAL);
    const ssize_t bytes = H5Fget_file_image(impl_->file.getId(), nullptr, 0);
    if (bytes < 0) throw H5::FileIException("H5Fget_file_image", "cannot size the file image");
    image.resize(static_cast<std::size_t>(bytes));
    if (H5Fget_file_image(impl_->file.getId(), image.data(), image.size()) != bytes)
      throw H5::FileIException("H5Fget_file_image", "cannot copy the file image");
    impl_->file.close();  // Frees the in-memory file before the copy is used.
    impl_->open = false;
  });
  return image;
}

// The bytes H5Fget_file_image would copy (the file's first `eoa` bytes, consistency flags
// cleared) are written from the driver's buffer, then the file is closed. Only when HDF5 has
// allocated more than it has written (eoa beyond the buffer; the driver reads zeros there) or the
// superblock is not one ClearStatusFlags knows is the image copied out first, as before.
// Backing::kFile: the buffer is the temporary file; what HDF5 writes while it closes goes to a
// private copy of the mapping (MAP_FIXED over it), so the file keeps exactly those bytes; it is
// then cut to `eoa`, synced and renamed.
void H5Writer::Commit() {
  impl_->Flush();
  const char* data = nullptr;
  std::size_t size = 0;
  Guard(final_path(), "close", [&] {
    impl_->file.flush(H5F_SCOPE_GLOBAL);
    const ssize_t bytes = H5Fget_file_image(impl_->file.getId(), nullptr, 0);
    if (bytes < 0) throw H5::FileIException("H5Fget_file_image", "cannot size the file image");
    size = static_cast<std::size_t>(bytes);
    if (impl_->image.data && size <= impl_->image.size &&
        ClearStatusFlags(static_cast<unsigned char*>(impl_->image.data), size))
      data = static_cast<const char*>(impl_->image.data);
  });
  if (impl_->image.error != 0) throw WriteError(final_path(), impl_->image.error);
  if (!data || impl_->image.fd < 0) {
    if (!data) {
      const std::vector<char> image = CloseToImage();
      WriteFileAtomic(final_path(), image.data(), image.size());
    } else {
      WriteFileAtomic(final_path(), data, size);
    }
    Guard(final_path(), "close", [&] {
      if (impl_->open) impl_->file.close();
      impl_->open = false;
    });
    return;  // The temporary file (if any) is removed with the writer.
  }
  CoreImage& image = impl_->image;
  if (mmap(image.data, image.mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_FIXED, image.fd,
           0) == MAP_FAILED)
    throw WriteError(final_path(), errno);
  Guard(final_path(), "close", [&] {
    impl_->file.close();
    impl_->open = false;
  });
  int error = ftruncate(image.fd, static_cast<off_t>(size)) != 0 ? errno : 0;
  // A file system may only report a full disk when the data reaches it (fsync) or at close.
  if (error == 0 && fsync(image.fd) != 0 && errno != EINVAL && errno != EROFS) error = errno;
  const int close_error = impl_->CloseSpill();
  if (error == 0) error = close_error;
  if (error != 0) throw WriteError(final_path(), error);
  impl_->spill->Commit();
}

std::vector<char> H5Writer::CommitToMemory() { return CloseToImage(); }

struct H5Reader::Impl {
  std::string path;
  H5::H5File file;
  std::set<std::string> datasets_read;  // Normalised paths, for DatasetsRead().
};

H5Reader::H5Reader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  H5::Exception::dontPrint();
  impl_->path = path;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Error(ErrorKind::kFileNotFound, "HDF5 file", "", "an existing .h5 file").WithFile(path);
  }
  try {
    impl_->file = H5::H5File(path, H5F_ACC_RDONLY);
  } catch (const H5::Exception& e) {
    throw Error(ErrorKind::kFileFormat, "HDF5 file",
                "a file HDF5 cannot open (" + e.getDetailMsg() + ")", "an HDF5 file")
        .WithFile(path);
  }
}

H5Reader::H5Reader(const std::string& name, const std::vector<char>& image)
    : impl_(std::make_unique<Impl>()) {
  H5::Exception::dontPrint();
  impl_->path = name;
  try {
    H5::FileAccPropList access;
    access.setCore(kCoreIncrement, /*backing_store=*/false);
    if (H5Pset_file_image(access.getId(), const_cast<char*>(image.data()), image.size()) < 0)
      throw H5::PropListIException("H5Pset_file_image", "cannot use the file image");
    impl_->file =
        H5::H5File(ImageName(name), H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, access);
  } catch (const H5::Exception& e) {
    throw Error(ErrorKind::kFileFormat, "HDF5 file image",
                "bytes HDF5 cannot open (" + e.getDetailMsg() + ")", "an HDF5 file image")
        .WithFile(name);
  }
}

H5Reader::~H5Reader() = default;

bool H5Reader::Exists(const std::string& path) const {
  const std::string p = Normalise(path);
  if (p == "/") return true;
  // nameExists fails if an intermediate group is missing; check each level.
  std::string current;
  for (const auto& part : SplitPath(p)) {
    current += "/" + part;
    if (!impl_->file.nameExists(current)) return false;
  }
  return true;
}

Dims H5Reader::Dimensions(const std::string& path) const {
  if (!Exists(path)) {
    throw Error(ErrorKind::kFileFormat, "dataset " + path, "missing", "the dataset to exist")
        .WithFile(impl_->path);
  }
  return Guard(impl_->path, "dataset " + path, [&] {
    H5::DataSet ds = impl_->file.openDataSet(Normalise(path));
    H5::DataSpace space = ds.getSpace();
    std::vector<hsize_t> h(space.getSimpleExtentNdims());
    space.getSimpleExtentDims(h.data());
    return Dims(h.begin(), h.end());
  });
}

namespace {

template <typename T>
std::vector<T> ReadAs(const H5::H5File& file, const std::string& file_name, const std::string& path,
                      const H5::PredType& type, Dims* dims, const Dims& shape) {
  const std::size_t count =
      std::accumulate(shape.begin(), shape.end(), std::size_t{1}, std::multiplies<>());
  std::vector<T> data(count);
  Guard(file_name, "dataset " + path, [&] {
    H5::DataSet ds = file.openDataSet(path);
    if (count > 0) ds.read(data.data(), type);
  });
  if (dims) *dims = shape;
  return data;
}

}  // namespace

std::vector<double> H5Reader::ReadDouble(const std::string& path, Dims* dims) const {
  const Dims shape = Dimensions(path);
  impl_->datasets_read.insert(Normalise(path));
  return ReadAs<double>(impl_->file, impl_->path, Normalise(path), H5::PredType::NATIVE_DOUBLE,
                        dims, shape);
}
std::vector<float> H5Reader::ReadFloat(const std::string& path, Dims* dims) const {
  const Dims shape = Dimensions(path);
  impl_->datasets_read.insert(Normalise(path));
  return ReadAs<float>(impl_->file, impl_->path, Normalise(path), H5::PredType::NATIVE_FLOAT, dims,
                       shape);
}
std::vector<std::int32_t> H5Reader::ReadInt(const std::string& path, Dims* dims) const {
  const Dims shape = Dimensions(path);
  impl_->datasets_read.insert(Normalise(path));
  return ReadAs<std::int32_t>(impl_->file, impl_->path, Normalise(path), H5::PredType::NATIVE_INT32,
                              dims, shape);
}

namespace {

H5::Attribute OpenAttribute(const H5::H5File& file, const std::string& object_path,
                            const std::string& name) {
  const std::string path = Normalise(object_path);
  if (path != "/" && file.childObjType(path) == H5O_TYPE_DATASET) {
    return file.openDataSet(path).openAttribute(name);
  }
  return file.openGroup(path).openAttribute(name);
}

}  // namespace

bool H5Reader::HasAttribute(const std::string& object_path, const std::string& name) const {
  if (!Exists(object_path)) return false;
  const std::string path = Normalise(object_path);
  return Guard(impl_->path, "attribute " + name, [&] {
    if (path != "/" && impl_->file.childObjType(path) == H5O_TYPE_DATASET) {
      return impl_->file.openDataSet(path).attrExists(name);
    }
    return impl_->file.openGroup(path).attrExists(name);
  });
}

std::string H5Reader::ReadStringAttribute(const std::string& object_path,
                                          const std::string& name) const {
  if (!HasAttribute(object_path, name)) {
    throw Error(ErrorKind::kFileFormat, "attribute " + name + " of " + object_path, "missing",
                "the attribute to exist")
        .WithFile(impl_->path);
  }
  return Guard(impl_->path, "attribute " + name, [&] {
    H5::Attribute attr = OpenAttribute(impl_->file, object_path, name);
    H5::StrType type = attr.getStrType();
    std::string value;
    attr.read(type, value);
    return value;
  });
}

double H5Reader::ReadNumberAttribute(const std::string& object_path,
                                     const std::string& name) const {
  if (!HasAttribute(object_path, name)) {
    throw Error(ErrorKind::kFileFormat, "attribute " + name + " of " + object_path, "missing",
                "the attribute to exist")
        .WithFile(impl_->path);
  }
  return Guard(impl_->path, "attribute " + name, [&] {
    H5::Attribute attr = OpenAttribute(impl_->file, object_path, name);
    double value = 0;
    attr.read(H5::PredType::NATIVE_DOUBLE, &value);
    return value;
  });
}

std::vector<std::string> H5Reader::List(const std::string& group_path) const {
  return GroupMembers(impl_->file, impl_->path, group_path);
}

bool H5Reader::IsGroup(const std::string& path) const {
  const std::string p = Normalise(path);
  if (p == "/") return true;
  if (!Exists(p)) return false;
  return Guard(impl_->path, "object " + p,
               [&] { return impl_->file.childObjType(p) == H5O_TYPE_GROUP; });
}

std::vector<std::string> H5Reader::AttributeNames(const std::string& object_path) const {
  const std::string p = Normalise(object_path);
  if (!Exists(p)) {
    throw Error(ErrorKind::kFileFormat, "object " + p, "missing", "the group or dataset to exist")
        .WithFile(impl_->path);
  }
  return Guard(impl_->path, "attributes of " + p, [&] {
    const auto names = [](const H5::H5Object& object) {
      std::vector<std::string> v(static_cast<std::size_t>(object.getNumAttrs()));
      for (std::size_t k = 0; k < v.size(); ++k)
        v[k] = object.openAttribute(static_cast<unsigned>(k)).getName();
      return v;
    };
    if (p != "/" && impl_->file.childObjType(p) == H5O_TYPE_DATASET)
      return names(impl_->file.openDataSet(p));
    return names(impl_->file.openGroup(p));
  });
}

bool H5Reader::IsTextAttribute(const std::string& object_path, const std::string& name) const {
  if (!HasAttribute(object_path, name)) {
    throw Error(ErrorKind::kFileFormat, "attribute " + name + " of " + object_path, "missing",
                "the attribute to exist")
        .WithFile(impl_->path);
  }
  return Guard(impl_->path, "attribute " + name, [&] {
    return OpenAttribute(impl_->file, object_path, name).getTypeClass() == H5T_STRING;
  });
}

std::vector<std::string> H5Reader::DatasetsRead() const {
  return {impl_->datasets_read.begin(), impl_->datasets_read.end()};
}

H5Reader::NumberType H5Reader::Type(const std::string& path) const {
  Dimensions(path);  // Error kFileFormat if it is missing.
  return Guard(impl_->path, "dataset " + path, [&] {
    H5::DataSet ds = impl_->file.openDataSet(Normalise(path));
    NumberType type;
    type.bytes = ds.getDataType().getSize();
    if (ds.getTypeClass() == H5T_INTEGER) {
      type.kind = ds.getIntType().getSign() == H5T_SGN_NONE ? NumberKind::kUInt : NumberKind::kInt;
    } else if (ds.getTypeClass() != H5T_FLOAT) {
      throw Error(ErrorKind::kFileFormat, "dataset " + path, "not numeric", "a numeric dataset")
          .WithFile(impl_->path);
    }
    return type;
  });
}

}  // namespace impactdic
