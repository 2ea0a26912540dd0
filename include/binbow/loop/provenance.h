// Where a run record or a report came from: the binbow that wrote it, when,
// and the command that ran, so that a result found on disk months later can
// be traced and reproduced. Filled by the caller (the CLI fills all three);
// written as given, left out when empty.
#pragma once

#include <string>

namespace binbow::loop {

struct Provenance {
  std::string binbow_version;  // e.g. "0.9.0"
  std::string date;            // UTC, ISO 8601: "2026-11-29T10:26:19Z"
  std::string command;         // the command line, quoted as a shell reads it back

  bool empty() const { return binbow_version.empty() && date.empty() && command.empty(); }
};

}  // namespace binbow::loop
