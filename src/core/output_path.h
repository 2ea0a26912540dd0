// Output paths made ready before a command starts its work, so that a missing
// folder is created and a blocked or read-only one fails at once, not after
// minutes of feature extraction or clustering.
#pragma once

#include <string>

namespace binbow::detail {

// Makes `path` ready to be written as a file: creates its missing parent
// folders and checks that its folder is writable (for an output written in
// place, see is_written_in_place, that it can be written itself). Throws FileError naming
// `path`, the cause and what to do when `path` names a directory, when a
// parent is a file, or when the folder cannot be created or written.
void prepare_output_file(const std::string& path);

// Whether a save to `path` writes into it in place instead of replacing it
// (symbolic links followed), decided by what `path` already is:
//  - a regular file, a directory or nothing: false (replaced or created);
//  - a character device (/dev/null, a terminal) or a FIFO: true, what a user
//    means by naming one as an output;
//  - /dev/stdout, /dev/stderr, /dev/fd/N: true, written through the
//    process's own descriptor (see own_descriptor), whatever it is open on;
//  - a block device or a socket: never a place for binbow's output; throws
//    FileError naming `path` and what it is.
bool is_written_in_place(const std::string& path);

// The descriptor number N when `path` names one of the process's own open
// descriptors (/proc/self/fd/N, or a link to it such as /dev/stdout and
// /dev/fd/N); -1 otherwise.
int own_descriptor(const std::string& path);

// Makes `path` ready to receive files: creates it and its missing parents and
// checks that it is writable. Throws FileError naming `path`, the cause and
// what to do when it exists as a file or cannot be created or written.
void prepare_output_directory(const std::string& path);

}  // namespace binbow::detail
