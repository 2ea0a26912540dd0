// --descriptor of the commands that read a vocabulary without extracting
// features (convert, info, db remove): the extractor the vocabulary was
// trained on, for files that do not record it (load_vocabulary). The image
// commands take it with their extractor flags (extractor_options.h).
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "formats/loader.h"

namespace binbow::cli {

// Adds --descriptor NAME; `use` says what else it does for this command.
void add_trained_on_option(CLI::App* command, std::string& descriptor, const std::string& use);

// InvalidArgument unless `descriptor` names an extractor binbow has (the
// vision module knows them).
void check_known_descriptor(const std::string& descriptor);
// InvalidArgument unless extractor `descriptor` makes descriptors of the
// vocabulary's length.
void check_descriptor_length(const std::string& descriptor, const Vocabulary& vocabulary);

// load_vocabulary_with_details with --descriptor, printing the loader's
// warning (a file that does not record its extractor, none given) once, and
// checking that a given extractor fits.
detail::LoadedVocabulary load_vocabulary_trained_on(const std::string& path,
                                                    VocabularyFormat format,
                                                    const std::string& descriptor);

}  // namespace binbow::cli
