// Where the bundled default vocabularies are found, so that commands can
// default --vocab to them.
#pragma once

#include <string>
#include <vector>

#include "binbow/vocabulary.h"

namespace binbow::cli {

// Whether binbow bundles a default vocabulary for this descriptor (orb, brief).
bool has_default_vocabulary(const std::string& descriptor);
// File name of the default vocabulary of a descriptor: "orb_default.bbw" or
// "brief_default.bbw". Throws InvalidArgument, saying to pass --vocab, for
// other descriptors.
std::string default_vocabulary_name(const std::string& descriptor);
// A usage error (CLI::ValidationError) saying to pass --vocab when it is
// empty and `descriptor` (kDefaultDescriptor when empty) has no default
// vocabulary: checked before any work.
void check_vocabulary_given(const std::string& vocab_argument, const std::string& descriptor);

// The places searched for it: vocab/ in each of data_directories().
std::vector<std::string> default_vocabulary_candidates(const std::string& descriptor);

// The bundled data directories, in search order:
//   1. $BINBOW_DATA_DIR                (explicit override)
//   2. <exe>/../share/binbow           (installed: bin/binbow beside share/binbow;
//                                       in a build tree, a link to the source's
//                                       data/ made at configure time)
// where <exe> is the directory of the running binbow executable.
std::vector<std::string> data_directories();
// The first existing <data directory>/<relative>; throws InvalidArgument
// naming `what` and the places searched when there is none.
std::string find_bundled_data(const std::string& relative, const std::string& what);

// The first existing candidate. Throws InvalidArgument, listing the places
// searched and telling the user to pass --vocab, when none exists.
std::string default_vocabulary_path(const std::string& descriptor);

// Throws InvalidArgument, naming `vocabulary_name` and saying what to pass
// instead, unless the vocabulary fits descriptors of extractor `descriptor`
// with `code_size` bytes: same length, and trained on that extractor when
// the vocabulary records one. Warns when every word weighs 0 (legal, but no
// image can be told from another). A vocabulary read from a file that does
// not record its extractor was named, or warned about, by load_vocabulary.
void check_vocabulary_fits(const Vocabulary& vocabulary, const std::string& vocabulary_name,
                           const std::string& descriptor, std::size_t code_size);

// The extractor of a command with a vocabulary: `given` (--descriptor, ""
// when not given), else the one the vocabulary records, else
// kDefaultDescriptor. A --descriptor that conflicts with the one the
// vocabulary records is refused by check_vocabulary_fits: the words of one
// extractor do not describe another's descriptors, even of the same size
// (record the right one with `binbow convert --descriptor`).
std::string descriptor_for(const std::string& given, const Vocabulary& vocabulary);

// --vocab, or the default vocabulary of `descriptor` (kDefaultDescriptor when
// empty) when --vocab is empty; loads it (a file that does not record its
// extractor takes `descriptor`, see load_vocabulary), sets `descriptor` by descriptor_for
// and checks that the vocabulary fits it (check_vocabulary_fits). Returns the
// absolute path.
std::string load_loop_vocabulary(const std::string& vocab_argument, std::string& descriptor,
                                 Vocabulary& vocabulary);

}  // namespace binbow::cli
