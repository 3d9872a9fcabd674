#include "impactdic/io/results_io.h"

#include <fmt/format.h>

#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

std::string DimsText(const Dims& dims) {
  std::string s = "[";
  for (std::size_t i = 0; i < dims.size(); ++i) s += (i ? " x " : "") + std::to_string(dims[i]);
  return s + "]";
}

}  // namespace

void RequireGroup(const H5Reader& in, const std::string& group, const std::string& file,
                  const std::string& what) {
  if (!in.Exists(group)) throw Error(ErrorKind::kFileFormat, group, "missing", what).WithFile(file);
}

std::vector<double> ReadSeries(const H5Reader& in, const std::string& path, const std::string& file,
                               std::size_t* length) {
  Dims dims;
  std::vector<double> v = in.ReadDouble(path, &dims);
  const bool any = *length == kAnyLength;
  if (dims.size() != 1 || (!any && dims[0] != *length)) {
    throw Error(ErrorKind::kFileFormat, path, DimsText(dims),
                any ? std::string("a series [K]")
                    : fmt::format("a series [{}] like the others of its group", *length))
        .WithFile(file);
  }
  *length = dims[0];
  return v;
}

std::vector<double> ReadField(const H5Reader& in, const std::string& path, const std::string& file,
                              const Dims& dims) {
  Dims found;
  std::vector<double> v = in.ReadDouble(path, &found);
  if (found != dims) {
    throw Error(ErrorKind::kFileFormat, path, DimsText(found),
                DimsText(dims) + " like the others of its group")
        .WithFile(file);
  }
  return v;
}

double ReadNumberAttributeOr(const H5Reader& in, const std::string& object, const std::string& name,
                             double absent) {
  return in.HasAttribute(object, name) ? in.ReadNumberAttribute(object, name) : absent;
}

std::string ReadStringAttributeOr(const H5Reader& in, const std::string& object,
                                  const std::string& name, const std::string& absent) {
  return in.HasAttribute(object, name) ? in.ReadStringAttribute(object, name) : absent;
}

void WriteNumberAttributes(H5Writer& out, const std::string& object,
                           const std::vector<std::pair<const char*, double>>& attributes) {
  for (const auto& [name, value] : attributes) out.SetAttribute(object, name, value);
}

void ReadNumberAttributes(const H5Reader& in, const std::string& object,
                          const std::vector<std::pair<const char*, double*>>& attributes) {
  for (const auto& [name, value] : attributes)
    *value = ReadNumberAttributeOr(in, object, name, std::numeric_limits<double>::quiet_NaN());
}

}  // namespace impactdic
