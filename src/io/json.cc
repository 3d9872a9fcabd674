#include "impactdic/io/json.h"

#include <fmt/format.h>

#include <cmath>
#include <cstddef>

namespace impactdic {

std::string JsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  return fmt::format("{:.17g}", value);
}

std::string JsonString(const std::string& value) {
  std::string out = "\"";
  for (unsigned char c : value) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          out += fmt::format("\\u{:04x}", static_cast<int>(c));
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

JsonObject& JsonObject::Add(const std::string& key, double value) {
  members_.emplace_back(key, JsonNumber(value));
  return *this;
}
JsonObject& JsonObject::Add(const std::string& key, int value) {
  members_.emplace_back(key, std::to_string(value));
  return *this;
}
JsonObject& JsonObject::Add(const std::string& key, std::int64_t value) {
  members_.emplace_back(key, std::to_string(value));
  return *this;
}
JsonObject& JsonObject::Add(const std::string& key, bool value) {
  members_.emplace_back(key, value ? "true" : "false");
  return *this;
}
JsonObject& JsonObject::Add(const std::string& key, const std::string& value) {
  members_.emplace_back(key, JsonString(value));
  return *this;
}
JsonObject& JsonObject::Add(const std::string& key, const char* value) {
  return Add(key, std::string(value));
}
JsonObject& JsonObject::Add(const std::string& key, const std::vector<double>& values) {
  std::string s = "[";
  for (std::size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + JsonNumber(values[i]);
  members_.emplace_back(key, s + "]");
  return *this;
}
JsonObject& JsonObject::Add(const std::string& key, const std::vector<std::string>& values) {
  std::string s = "[";
  for (std::size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + JsonString(values[i]);
  members_.emplace_back(key, s + "]");
  return *this;
}
JsonObject& JsonObject::Add(const std::string& key, const JsonObject& object) {
  members_.emplace_back(key, object.Dump(0));
  return *this;
}
JsonObject& JsonObject::AddNull(const std::string& key) {
  members_.emplace_back(key, "null");
  return *this;
}

std::string JsonObject::Dump(int indent) const {
  if (members_.empty()) return "{}";
  const std::string pad(indent, ' ');
  const char* sep = indent > 0 ? ",\n" : ", ";
  std::string out = indent > 0 ? "{\n" : "{";
  for (std::size_t i = 0; i < members_.size(); ++i) {
    if (i) out += sep;
    out += pad + JsonString(members_[i].first) + ": " + members_[i].second;
  }
  return out + (indent > 0 ? "\n}" : "}");
}

}  // namespace impactdic
