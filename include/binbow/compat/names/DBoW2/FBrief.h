// DBoW2's include name <DBoW2/FBrief.h>, as DBoW2 installs it: binbow's
// DBoW2-compatible header of the same name. Nothing more: DBoW2's own header
// brings nothing else. Found through the opt-in target binbow::dbow2_names
// (pkg-config binbow-dbow2-names).
#include "binbow/compat/FBrief.h"
