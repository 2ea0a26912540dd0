// How binbow was invoked, for every command: the command line and the time
// the run started, which run records and reports carry so that a result can
// be traced to the binbow and the command that produced it, and --quiet.
// main() fills the executable's copy before the command runs; the
// binbow_cli_vision module reads that copy too (vision_commands.h), as it
// reads the executable's interruption flag.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace binbow::cli {

struct Invocation {
  std::string command_line;  // argv, quoted as a POSIX shell reads it back
  std::string started_utc;   // ISO 8601, e.g. "2026-11-29T10:26:19Z"
  // --quiet: no progress and no informational lines; results asked for
  // (tables, --json), warnings and errors still print.
  bool quiet = false;
};

const Invocation& invocation() noexcept;
// The executable's copy, for main() to fill.
Invocation& own_invocation() noexcept;
// Makes invocation() read `watched` (the executable's copy, from the module).
void watch_invocation(const Invocation* watched) noexcept;

// `arguments` joined by spaces, each quoted where a POSIX shell would split
// or expand it: 'a b' stays one argument when pasted back into a shell.
std::string shell_quoted(const std::vector<std::string>& arguments);
// The current UTC time as ISO 8601, to the second.
std::string utc_now();

// Where the human-readable summary of a command whose product is a file
// (detect-loops, build-vocab, convert, db build, make-route) goes: stdout,
// stderr when stdout carries the product itself (`-o -`), nowhere (null)
// with --quiet.
std::FILE* summary_stream(bool product_on_stdout) noexcept;
// printf to summary_stream(product_on_stdout), if any.
void print_summary(bool product_on_stdout, const char* format, ...)
    __attribute__((format(printf, 2, 3)));
// printf to stderr unless --quiet: the informational lines that are not
// results ("report: DIR/index.html", "resuming after ...").
void note(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace binbow::cli
