// results.xdmf: the subset grid and its fields per analysed frame, described in XDMF 3 for
// ParaView, VisIt and meshio, without copying results.h5's data (layout: io/results_layout.h,
// kXdmfFile; docs/results.md, docs/render.md "ParaView and VisIt").
//
// An XDMF reader takes the heavy data from HDF5 datasets, either whole or by hyperslab. meshio
// (and other light readers) take only whole datasets, so the rows of results.h5's [F x N]
// datasets are offered as whole datasets: /xdmf in results.h5 holds HDF5 virtual datasets
// (H5Writer::WriteView), one per frame and field, that map row f of the source and store
// nothing. The results writer writes them (WriteXdmfViews, before it commits results.h5); this
// writer then lists them in the XML. The only data of /xdmf is the Polyvertex connectivity
// 0..N-1 (4 N bytes).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <array>
#include <cstdint>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/log.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/pipeline.h"
#include "writers.h"

namespace impactdic::outputs {
namespace L = results_layout;
namespace {

// [F x N] datasets of /dic shown per frame as scalars (every [F x N] dataset of /strain is too).
constexpr std::array<const char*, 7> kDicScalars = {
    L::kDicStatus,   L::kDicZncc,     L::kDicSigma,   L::kDicDudxWarp,
    L::kDicDudyWarp, L::kDicDvdxWarp, L::kDicDvdyWarp};

// Pairs of [F x N] datasets shown per frame as one 3-vector (x, y, 0): ParaView's glyphs and
// "Warp By Vector" take 3 components.
struct VectorField {
  const char* name;
  const char* x;
  const char* y;
  const char* units;
};
constexpr std::array<VectorField, 4> kVectors = {{
    {"displacement_px", L::kDicU, L::kDicV, "px"},
    {"displacement_mm", L::kUxMm, L::kUyMm, "mm"},
    {"velocity_mm_s", L::kVx, L::kVy, "mm/s"},
    {"acceleration_mm_s2", L::kAx, L::kAy, "mm/s^2"},
}};

std::string FrameGroup(std::size_t f) { return fmt::format("{}{:06d}", L::kXdmfFramePrefix, f); }

std::string LeafName(const std::string& path) { return path.substr(path.find_last_of('/') + 1); }

// The [F x N] datasets shown as scalars: those of kDicScalars present, then /strain's members.
std::vector<std::string> ScalarSources(const H5Writer& out, const Dims& frame_by_subset) {
  std::vector<std::string> candidates(kDicScalars.begin(), kDicScalars.end());
  if (out.Exists(L::kStrainGroup)) {
    for (const std::string& name : out.List(L::kStrainGroup))
      candidates.push_back(std::string(L::kStrainGroup) + "/" + name);
  }
  std::vector<std::string> sources;
  for (const std::string& path : candidates) {
    if (out.Exists(path) && out.Dimensions(path) == frame_by_subset) sources.push_back(path);
  }
  return sources;
}

// The number type of a dataset as XDMF names it (DataType, Precision).
std::string XdmfNumberType(const H5Reader::NumberType& type) {
  const char* kind = type.kind == H5Reader::NumberKind::kFloat ? "Float"
                     : type.kind == H5Reader::NumberKind::kInt ? "Int"
                                                               : "UInt";
  return fmt::format("DataType=\"{}\" Precision=\"{}\"", kind, type.bytes);
}

// <DataItem> of a whole dataset of results.h5 (the path is relative to results.xdmf).
std::string DataItem(const H5Reader& in, const std::string& path) {
  return fmt::format("<DataItem Dimensions=\"{}\" {} Format=\"HDF\">{}:{}</DataItem>",
                     fmt::join(in.Dimensions(path), " "), XdmfNumberType(in.Type(path)),
                     L::kResultsFile, path);
}

// One frame's Grid: the shared topology and geometry (repeated by reference, no data), the
// frame's time [ms since the impact] and its fields.
std::string FrameGrid(const H5Reader& in, std::size_t f, double t_ms, std::size_t n) {
  const std::string group = FrameGroup(f);
  std::string xml = fmt::format("      <Grid Name=\"frame_{:06d}\" GridType=\"Uniform\">\n", f);
  xml += fmt::format("        <Time Value=\"{:.17g}\"/>\n", t_ms);
  xml += fmt::format(
      "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{}\" "
      "NodesPerElement=\"1\">\n          {}\n        </Topology>\n",
      n, DataItem(in, L::kXdmfVertices));
  xml += fmt::format("        <Geometry GeometryType=\"XY\">\n          {}\n        </Geometry>\n",
                     DataItem(in, L::kXdmfPoints));
  for (const std::string& name : in.List(group)) {
    const std::string path = fmt::format("{}/{}", group, name);
    const bool vector = in.Dimensions(path).size() == 2;
    xml += fmt::format(
        "        <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"Node\">\n          {}\n"
        "        </Attribute>\n",
        name, vector ? "Vector" : "Scalar", DataItem(in, path));
  }
  return xml + "      </Grid>\n";
}

class XdmfWriter : public OutputWriter {
 public:
  std::string name() const override { return L::kXdmfFile; }
  std::vector<std::string> FileNames() const override { return {L::kXdmfFile}; }
  std::string SkipReason(const Scene& scene, const SceneRunData&) const override {
    if (!scene.outputs.xdmf) return "outputs.xdmf is false";
    if (!scene.outputs.hdf5) return "outputs.hdf5 is false (results.xdmf describes results.h5)";
    return "";  // Without correlation results (no /xdmf in results.h5) Write writes nothing.
  }
  void Write(OutputContext& c) const override {
    const H5Reader in(c.results_path);
    if (!in.Exists(L::kXdmfPoints)) {
      LogInfo("[outputs] {} skipped: no subset fields in results.h5", L::kXdmfFile);
      return;
    }
    const std::vector<double> t_ms = in.ReadDouble(L::kTimeMs);
    const std::size_t n = in.Dimensions(L::kXdmfPoints)[0];
    std::string xml =
        "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
        "<!-- impactdic: the subsets of results.h5 per analysed frame (time in ms since the "
        "impact; positions in px, y down). -->\n"
        "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n  <Domain>\n"
        "    <Grid Name=\"subsets\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (std::size_t f = 0; f < t_ms.size(); ++f) xml += FrameGrid(in, f, t_ms[f], n);
    xml += "    </Grid>\n  </Domain>\n</Xdmf>\n";
    const std::string path = c.Path(L::kXdmfFile);
    WriteTextFileAtomic(path, xml);
    c.summary.outputs.push_back(path);
  }
};

}  // namespace

void WriteXdmfViews(H5Writer& out) {
  if (!out.Exists(L::kDicX) || !out.Exists(L::kDicY) || !out.Exists(L::kTimeMs)) return;
  const Dims positions = out.Dimensions(L::kDicX);
  if (positions.size() != 1 || out.Dimensions(L::kDicY) != positions) return;
  const std::size_t n = positions[0];
  const std::size_t frames = out.Dimensions(L::kTimeMs)[0];
  const Dims frame_by_subset{frames, n};
  out.Remove(L::kXdmfGroup);
  out.WriteView(L::kXdmfPoints, {n, 2}, {{L::kDicX, std::nullopt, 0}, {L::kDicY, std::nullopt, 1}},
                "px",
                "view of /dic/x_px, /dic/y_px: subset centres (x right, y down) for results.xdmf");
  std::vector<std::int32_t> vertices(n);
  std::iota(vertices.begin(), vertices.end(), 0);
  out.Write(L::kXdmfVertices, vertices, {n, 1}, "1",
            "Polyvertex connectivity of results.xdmf: subset k is vertex k");
  const std::vector<std::string> scalars = ScalarSources(out, frame_by_subset);
  std::vector<VectorField> vectors;
  for (const VectorField& v : kVectors) {
    if (out.Exists(v.x) && out.Exists(v.y) && out.Dimensions(v.x) == frame_by_subset &&
        out.Dimensions(v.y) == frame_by_subset)
      vectors.push_back(v);
  }
  for (std::size_t f = 0; f < frames; ++f) {
    const std::string group = FrameGroup(f);
    for (const std::string& source : scalars) {
      out.WriteView(group + "/" + LeafName(source), {n}, {{source, f, 0}}, "as " + source,
                    fmt::format("view of row {} of {}", f, source));
    }
    for (const VectorField& v : vectors) {
      out.WriteView(group + "/" + v.name, {n, 3}, {{v.x, f, 0}, {v.y, f, 1}}, v.units,
                    fmt::format("view of row {} of {} and {} (x, y, 0)", f, v.x, v.y));
    }
  }
  out.SetAttribute(L::kXdmfGroup, "description",
                   "views (HDF5 virtual datasets, no data of their own) of results.h5's subset "
                   "fields per frame, referenced by results.xdmf");
}

std::shared_ptr<const OutputWriter> MakeXdmfWriter() { return std::make_shared<XdmfWriter>(); }

}  // namespace impactdic::outputs
