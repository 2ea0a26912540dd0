// The include name "Thirdparty/DBoW2/DBoW2/TemplatedDatabase.h" of ORB-SLAM's copy of
// DBoW2: binbow's DBoW2-compatible header of the same name. The copy's
// TemplatedVocabulary.h brings what ORB-SLAM's code relies on; this one,
// like upstream DBoW2's, nothing more. Found through the opt-in target
// binbow::dbow2_names (pkg-config binbow-dbow2-names).
#include "binbow/compat/TemplatedDatabase.h"
