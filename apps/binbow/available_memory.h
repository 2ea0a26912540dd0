// How much more memory this process can take, for commands that refuse work
// they could not finish instead of dying out of memory.
#pragma once

#include <cstdint>
#include <string>

namespace binbow::cli {

// Bytes this process can still allocate: the least of the machine's
// MemAvailable (/proc/meminfo), its cgroup's memory.max less memory.current
// (cgroup v2), and its address-space limit (RLIMIT_AS, `ulimit -v`) less
// what it already maps. 0 when none of them can be read.
std::uint64_t available_memory();

// Bytes in GiB for a message: "7.3 GiB", "31 GiB".
std::string gibibytes(std::uint64_t bytes);

}  // namespace binbow::cli
