// The HDF5 result store: named datasets (1-D..4-D, float/double/int32) with `units` and
// `description` string attributes, string attributes on groups and datasets, nested groups.
// Files are plain HDF5 (row-major, native little-endian types, variable-length UTF-8 strings as
// attributes), so h5py, MATLAB's h5read/h5readatt and HDFView open them without conversion.
// (MATLAB shows the dimensions reversed, as for every row-major file.)
//
// A writer builds the file with HDF5's core driver (HDF5 itself never writes to the disk) in a
// temporary sibling mapped into memory a few MB at a time (Backing::kFile), and Commit() syncs it
// and renames it over the final name, only when complete. A writer destroyed without Commit()
// leaves nothing (the temporary file is removed); a full disk is one Error kIo naming the file
// ("no space left on device"), at the write that needs the room, with no temporary file left.
// The memory a writer holds does not grow with the file (Backing::kMemory: the whole file, once).
//
//   H5Writer out("run/results.h5");
//   out.WriteProvenance(scene_yaml_text);
//   out.Write("dic/u_px", u, {frames, rows, cols}, "px", "horizontal displacement, x right");
//   out.SetAttribute("dic", "interpolation", "bicubic");
//   out.Commit();
//
//   H5Reader in("run/results.h5");
//   std::vector<std::size_t> dims;
//   std::vector<double> u = in.ReadDouble("dic/u_px", &dims);
#ifndef IMPACTDIC_IO_HDF5_STORE_H_
#define IMPACTDIC_IO_HDF5_STORE_H_

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace impactdic {

using Dims = std::vector<std::size_t>;

class H5Writer {
 public:
  // Starts a new file; an existing file of that name is replaced on Commit(). Error kIo unless
  // the folder of `final_path` exists and is writable.
  explicit H5Writer(const std::string& final_path);
  // kUpdate: starts from the existing file at final_path, read into memory (Error if it is missing
  // or not HDF5), so groups can be added or replaced; the original stays untouched until Commit()
  // replaces it.
  // With `source_path`, kUpdate starts from that file instead (it is never changed) and Commit()
  // writes final_path: a changed copy (`analyze SCENE --output`).
  enum class Mode { kCreate, kUpdate };
  // Where the file is built until Commit(): kFile (the default) in a temporary file beside
  // final_path, mapped into memory a few MB at a time, so a file of any size holds about 4 MB of
  // the process's memory, and a full disk is an Error kIo naming final_path at the write that
  // needs the room (the space is reserved as the file grows); kMemory in memory only (nothing on
  // the disk before Commit(), e.g. for CommitToMemory), the whole file held once.
  enum class Backing { kFile, kMemory };
  H5Writer(const std::string& final_path, Mode mode, const std::string& source_path = "",
           Backing backing = Backing::kFile);
  // For a command that owns only `owned_groups` of a file it may share with others (correlate -o
  // owns /dic): a new file when final_path does not exist, else kUpdate with those groups removed,
  // so everything else in the file is kept. An existing file that is not HDF5 is an Error
  // kFileFormat naming it, and is never replaced.
  H5Writer(const std::string& final_path, const std::vector<std::string>& owned_groups);
  ~H5Writer();
  H5Writer(const H5Writer&) = delete;
  H5Writer& operator=(const H5Writer&) = delete;

  // Creates a group (and its parents); a no-op if it exists.
  void CreateGroup(const std::string& path);
  // Removes a group or dataset (and everything below it) if it exists.
  void Remove(const std::string& path);

  // Writes a dataset at `path` (parent groups are created). dims has 1..4 entries whose product
  // equals data.size(). Datasets of >= 4096 elements are chunked and deflate-compressed.
  void Write(const std::string& path, const std::vector<double>& data, const Dims& dims,
             const std::string& units, const std::string& description);
  void Write(const std::string& path, const std::vector<float>& data, const Dims& dims,
             const std::string& units, const std::string& description);
  void Write(const std::string& path, const std::vector<std::int32_t>& data, const Dims& dims,
             const std::string& units, const std::string& description);
  // Unsigned 8/16-bit (images); ReadInt/ReadFloat/ReadDouble read them converted.
  void Write(const std::string& path, const std::vector<std::uint8_t>& data, const Dims& dims,
             const std::string& units, const std::string& description);
  void Write(const std::string& path, const std::vector<std::uint16_t>& data, const Dims& dims,
             const std::string& units, const std::string& description);
  // A stack of F images [F x R x C] (dims) of unsigned 8-bit (bits 8) or 16-bit (bits 16)
  // values, written one image at a time: fill(f, buffer) fills the R*C values of image f into a
  // buffer of that type. One image is in memory at a time; each is one deflate-compressed chunk.
  void WriteStack(const std::string& path, const Dims& dims, int bits,
                  const std::function<void(std::size_t, void*)>& fill, const std::string& units,
                  const std::string& description);
  // 1-D convenience.
  void Write(const std::string& path, const std::vector<double>& data, const std::string& units,
             const std::string& description);

  // A view: an HDF5 virtual dataset at `path` of `dims` ([N] or [N x C]) that holds no data of its
  // own. Each part maps N values of a dataset already in this file -- row `row` of an [F x N]
  // one, or the whole of an [N] one (row unset) -- onto column `column` of the view (onto the
  // whole view when it is 1-D); what no part maps reads as 0. The view has the type of its first
  // part's source. Readers see an ordinary dataset (HDF5 >= 1.10; the source file is ".", this
  // file, so the file can be moved or renamed). For results.xdmf (pipeline outputs).
  struct ViewPart {
    std::string source;
    std::optional<std::size_t> row;
    std::size_t column = 0;
  };
  void WriteView(const std::string& path, const Dims& dims, const std::vector<ViewPart>& parts,
                 const std::string& units, const std::string& description);
  // Whether a group or dataset exists in the file being written; a dataset's dimensions; the
  // names of the members of a group.
  bool Exists(const std::string& path) const;
  Dims Dimensions(const std::string& path) const;
  std::vector<std::string> List(const std::string& group_path) const;

  // String / numeric attribute on an existing group or dataset ("/" is the root).
  void SetAttribute(const std::string& object_path, const std::string& name,
                    const std::string& value);
  void SetAttribute(const std::string& object_path, const std::string& name, double value);

  // Root attributes `tool`, `tool_version`, `git_revision`, `created_utc` and the dataset
  // `/provenance/scene_yaml` (the scene text, as a string attribute `text` of that group).
  void WriteProvenance(const std::string& scene_yaml_text);

  // Writes the file under its final name (atomically); Error kIo naming it if that fails.
  void Commit();
  // Closes the file and returns its bytes instead of writing them, for a reader in the same
  // process (H5Reader(name, image)): nothing is written under the final name (Backing::kMemory:
  // nothing at all is written to the disk).
  std::vector<char> CommitToMemory();
  const std::string& final_path() const;

 private:
  std::vector<char> CloseToImage();

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class H5Reader {
 public:
  explicit H5Reader(const std::string& path);
  // Reads a file held in memory (H5Writer::CommitToMemory; the bytes are copied); `name` stands
  // for the file in messages.
  H5Reader(const std::string& name, const std::vector<char>& image);
  ~H5Reader();
  H5Reader(const H5Reader&) = delete;
  H5Reader& operator=(const H5Reader&) = delete;

  bool Exists(const std::string& path) const;
  Dims Dimensions(const std::string& path) const;
  // Reads any numeric dataset converted to the requested type; `dims` (optional) receives the
  // shape. Error kFileFormat naming the file and the dataset if it is missing.
  std::vector<double> ReadDouble(const std::string& path, Dims* dims = nullptr) const;
  std::vector<float> ReadFloat(const std::string& path, Dims* dims = nullptr) const;
  std::vector<std::int32_t> ReadInt(const std::string& path, Dims* dims = nullptr) const;
  std::string ReadStringAttribute(const std::string& object_path, const std::string& name) const;
  double ReadNumberAttribute(const std::string& object_path, const std::string& name) const;
  bool HasAttribute(const std::string& object_path, const std::string& name) const;
  // Names of the members of a group.
  std::vector<std::string> List(const std::string& group_path) const;
  // Whether `path` is a group ("/" is one); false for a dataset or a missing path.
  bool IsGroup(const std::string& path) const;
  // The names of the attributes of a group or dataset, in the file's order, and whether one holds
  // text (else a number): what a reader of any file lists (the Python module's read_results).
  std::vector<std::string> AttributeNames(const std::string& object_path) const;
  bool IsTextAttribute(const std::string& object_path, const std::string& name) const;
  // The datasets read so far by ReadDouble / ReadFloat / ReadInt ("/dic/u_px", sorted, each
  // once): a test checks that the readers of a file's groups read every dataset in it.
  std::vector<std::string> DatasetsRead() const;
  // The stored element type of a numeric dataset: float, signed or unsigned integer, and its
  // size [bytes].
  enum class NumberKind { kFloat, kInt, kUInt };
  struct NumberType {
    NumberKind kind = NumberKind::kFloat;
    std::size_t bytes = 8;
  };
  NumberType Type(const std::string& path) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_IO_HDF5_STORE_H_
