// `binbow convert IN OUT [--from F] [--to F] [--descriptor NAME]`: a vocabulary
// from any readable format to any writable one (formats and extensions:
// docs/formats.md), naming the extractor it was trained on when IN does not
// record it (and recording it in a .bbw OUT).
#include <sys/stat.h>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "commands.h"
#include "formats/loader.h"
#include "invocation.h"
#include "output_options.h"
#include "trained_on_option.h"
#include "validators.h"

namespace binbow::cli {

namespace {

struct ConvertArguments {
  std::string input, output, from = "auto", to = "auto", descriptors = "auto";
  std::string descriptor;  // the extractor it was trained on, "" to keep the input's
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void run_convert(const ConvertArguments& args) {
  const VocabularyFormat from = parse_vocabulary_format(args.from);
  VocabularyFormat to = parse_vocabulary_format(args.to);
  // Standard output has no extension to tell the format: binbow's own.
  const bool on_stdout = is_standard_output(args.output);
  if (to == VocabularyFormat::kAuto)
    to = on_stdout ? VocabularyFormat::kBinbow : format_for_output(args.output);
  if (to != VocabularyFormat::kOrbSlamText && to != VocabularyFormat::kDbow2Yaml)
    refuse_binary_on_terminal("OUT", args.output, std::string("a ") + to_string(to) + " file");
  prepare_output_file("OUT", args.output);
  const std::string output = output_file(args.output);

  const auto start = std::chrono::steady_clock::now();
  detail::LoadedVocabulary loaded;
  try {
    loaded = load_vocabulary_trained_on(args.input, from, args.descriptor);
  } catch (const FileError& e) {
    if (e.problem().rfind(kUnknownVocabularyFormat, 0) != 0) throw;
    throw FileError(e.path(), e.problem() + " with --from");
  }
  print_summary(on_stdout, "read %s: %s%s, %s (%.3f s)\n", args.input.c_str(),
                to_string(loaded.format), loaded.compressed ? " (gzip)" : "",
                loaded.vocabulary.description().c_str(), seconds_since(start));
  if (!loaded.word_ids_match)
    note(
        "note: the file numbers its words in another order; binbow numbers them as the leaves "
        "appear in DBoW2's node order, so word ids differ from the file's\n");

  detail::DescriptorText text = loaded.descriptor_text;
  if (args.descriptors == "bits")
    text = detail::DescriptorText::kBits;
  else if (args.descriptors == "bytes")
    text = detail::DescriptorText::kBytes;
  if (to == VocabularyFormat::kFbow && (loaded.vocabulary.weighting() != Weighting::kTfIdf ||
                                        loaded.vocabulary.scoring() != Scoring::kL1))
    note(
        "note: fbow files store no weighting or scoring type; they read back as tf-idf, "
        "l1\n");
  // A .bbw that records another extractor is relabelled: that is how a
  // wrong name is corrected.
  if (!args.descriptor.empty() && loaded.vocabulary.descriptor() != args.descriptor)
    loaded.vocabulary = loaded.vocabulary.with_descriptor(args.descriptor);
  const std::string& trained_on = loaded.vocabulary.descriptor();
  if (to == VocabularyFormat::kBinbow && !args.descriptor.empty())
    print_summary(on_stdout, "descriptor: %s (recorded)\n", trained_on.c_str());
  if (to == VocabularyFormat::kVinsBinary && !trained_on.empty() && trained_on != "brief")
    note(
        "note: VINS files do not record the extractor and VINS computes BRIEF descriptors; "
        "this vocabulary was trained on %s ones\n",
        trained_on.c_str());
  else if (to != VocabularyFormat::kBinbow && to != VocabularyFormat::kVinsBinary &&
           !trained_on.empty() && trained_on != "orb")
    note(
        "note: %s files do not record the extractor: reading %s back assumes orb; give "
        "--descriptor %s then\n",
        to_string(to), args.output.c_str(), trained_on.c_str());

  const auto write_start = std::chrono::steady_clock::now();
  detail::save_vocabulary_as(loaded.vocabulary, output, to, text);
  struct stat st {};
  // The size of a file; a stream written in place has none to stat.
  const std::string size = !on_stdout && ::stat(output.c_str(), &st) == 0
                               ? ", " + std::to_string(st.st_size) + " bytes"
                               : "";
  print_summary(on_stdout, "wrote %s: %s%s%s (%.3f s)\n", args.output.c_str(), to_string(to),
                to == VocabularyFormat::kDbow2Yaml
                    ? (text == detail::DescriptorText::kBits ? " with bit-string descriptors"
                                                             : " with decimal-byte descriptors")
                    : "",
                size.c_str(), seconds_since(write_start));
}

}  // namespace

void add_convert_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "convert",
      "Convert a vocabulary between formats (bbw, ORB-SLAM text/binary, DBoW2 YAML, "
      "DBoW3, fbow, VINS binary)");
  auto args = std::make_shared<ConvertArguments>();
  cmd->add_option("IN", args->input, "Vocabulary to read (format detected from its content)")
      ->required();
  cmd->add_option("OUT", args->output,
                  std::string("File to write; its extension picks the format: .bbw, .txt "
                              "(ORB-SLAM text), .bin (ORB-SLAM binary), .vins.bin (VINS binary), "
                              ".yml/.yml.gz/.voc.gz (DBoW2 YAML), .dbow3, .fbow") +
                      kOutputFileHelp +
                      " (as .bbw unless --to says; binary formats only when redirected; the "
                      "summary then goes to stderr)")
      ->required();
  cmd->add_option("--from", args->from,
                  "Input format: auto, bbw, dbow2, orbslam-text, orbslam-binary, dbow3, fbow, "
                  "vins")
      ->check(parsed_by(parse_vocabulary_format))
      ->capture_default_str();
  cmd->add_option("--to", args->to,
                  "Output format (same names; auto: by OUT's extension; vins writes "
                  "VINS-Mono/VINS-Fusion's brief_k10L6.bin layout whatever the extension)")
      ->check(parsed_by(parse_vocabulary_format))
      ->capture_default_str();
  cmd->add_option("--descriptors", args->descriptors,
                  "DBoW2 YAML output: bits (FBrief 0/1 strings, DLoopDetector/VINS), bytes "
                  "(FORB decimal bytes) or auto (as the input file, else bytes)")
      ->check(CLI::IsMember({"auto", "bits", "bytes"}))
      ->capture_default_str();
  add_trained_on_option(cmd, args->descriptor,
                        "A .bbw OUT records it (relabelling a .bbw IN that records another)");
  cmd->callback([args] { run_convert(*args); });
}

}  // namespace binbow::cli
