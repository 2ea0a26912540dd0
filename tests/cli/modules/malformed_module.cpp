// Shared objects that export the CLI module's entry symbol but are not the
// module: the CLI must refuse each with an error naming what is wrong, and
// read nothing of them it has not checked. Built once per MALFORMED_* kind
// (tests/CMakeLists.txt).

// The layout every module table begins with (core/module_entry.h), then
// room for the function pointers of a whole table.
struct Table {
  int version;
  const char* binbow_version;
  void* functions[32];
};

#define EXPORTED extern "C" __attribute__((visibility("default")))

#if defined(MALFORMED_DATA_SYMBOL)
// Data under the entry point's name: calling it would jump into data.
EXPORTED const int binbow_cli_vision_commands[4] = {1, 2, 3, 4};
#else
namespace {
#if defined(MALFORMED_VERSION_POINTER)
const Table kTable{1, reinterpret_cast<const char*>(0x10), {}};
#elif defined(MALFORMED_OTHER_INTERFACE)
const Table kTable{1000, BINBOW_VERSION, {}};
#elif defined(MALFORMED_OTHER_RELEASE)
const Table kTable{1, "0.0.0-other", {}};
#endif
}  // namespace

// The entry point's own type, so that calling it is not itself the fault
// (UBSan's -fsanitize=function checks the type a function is called as).
namespace binbow::cli {
struct VisionCommands;
}

EXPORTED const binbow::cli::VisionCommands* binbow_cli_vision_commands() {
#if defined(MALFORMED_TABLE_ADDRESS)
  return reinterpret_cast<const binbow::cli::VisionCommands*>(0x10);
#else
  return reinterpret_cast<const binbow::cli::VisionCommands*>(&kTable);
#endif
}
#endif
