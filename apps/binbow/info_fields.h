// What `binbow info` says about a file or the system: fields in order,
// printed as `key: value` lines or, with --json, as one JSON object with the
// same keys (numbers as numbers) and "binbow_version" first.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

namespace binbow::cli {

class InfoFields {
 public:
  using Json = nlohmann::ordered_json;

  void add(const std::string& key, Json value) { fields_[key] = std::move(value); }

  void print(bool json) const {
    if (json) {
      Json object = {{"binbow_version", BINBOW_VERSION}};
      object.update(fields_);
      std::printf("%s\n", object.dump(2).c_str());
      return;
    }
    for (const auto& [key, value] : fields_.items())
      std::printf("%s: %s\n", key.c_str(),
                  value.is_string() ? value.get<std::string>().c_str() : value.dump().c_str());
  }

 private:
  Json fields_ = Json::object();
};

// A CRC-32C as the files' tools print it: eight hexadecimal digits.
inline std::string hex_checksum(std::uint32_t checksum) {
  char text[9];
  std::snprintf(text, sizeof text, "%08x", checksum);
  return text;
}

}  // namespace binbow::cli
