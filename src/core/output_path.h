// Output paths made ready before a command starts its work, so that a missing
// folder is created and a blocked or read-only one fails at once, not after
// minutes of feature extraction or clustering.
#pragma once

#include <string>

namespace binbow::detail {

// Makes `path` ready to be written as a file: creates its missing parent
// folders and checks that its folder is writable. Throws FileError naming
// `path`, the cause and what to do when `path` names a directory, when a
// parent is a file, or when the folder cannot be created or written.
void prepare_output_file(const std::string& path);

// Makes `path` ready to receive files: creates it and its missing parents and
// checks that it is writable. Throws FileError naming `path`, the cause and
// what to do when it exists as a file or cannot be created or written.
void prepare_output_directory(const std::string& path);

}  // namespace binbow::detail
