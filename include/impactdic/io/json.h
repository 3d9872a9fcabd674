// A small ordered JSON object writer for the CLI's --format json outputs (NaN and inf become null,
// as the CLI contracts require).
//
//   JsonObject j;
//   j.Add("t_end_s", 0.0123).Add("solver", "dopri5").Add("warnings", std::vector<std::string>{});
//   std::cout << j.Dump() << "\n";
#ifndef IMPACTDIC_IO_JSON_H_
#define IMPACTDIC_IO_JSON_H_

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace impactdic {

class JsonObject {
 public:
  JsonObject& Add(const std::string& key, double value);
  JsonObject& Add(const std::string& key, int value);
  JsonObject& Add(const std::string& key, std::int64_t value);
  JsonObject& Add(const std::string& key, bool value);
  JsonObject& Add(const std::string& key, const std::string& value);
  JsonObject& Add(const std::string& key, const char* value);
  JsonObject& Add(const std::string& key, const std::vector<double>& values);
  JsonObject& Add(const std::string& key, const std::vector<std::string>& values);
  JsonObject& Add(const std::string& key, const JsonObject& object);
  JsonObject& AddNull(const std::string& key);

  // Compact (indent = 0) or pretty-printed with `indent` spaces.
  std::string Dump(int indent = 2) const;

 private:
  std::vector<std::pair<std::string, std::string>> members_;  // key, already-encoded value
};

// JSON encodings of single values (shared with CSV summaries): numbers with 17 significant digits.
std::string JsonNumber(double value);
std::string JsonString(const std::string& value);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_JSON_H_
