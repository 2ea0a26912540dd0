// The include name "ThirdParty/DBoW/DBoW2.h" of VINS-Mono/Fusion's copy of
// DBoW2: binbow's DBoW2-compatible API with what the copy brought along, so
// that VINS's code builds unchanged:
// - its BRIEF descriptors, DVision::BRIEF (ThirdParty/DVision/DVision.h,
//   which the copy's FBrief.h includes), accepted by BriefVocabulary and
//   BriefDatabase as std::vector<BRIEF::bitset>;
// - its query rule: every database of the program considers the newest
//   entry in L1_NORM queries, as the copy's queryL1 does
//   (TemplatedDatabase::setVinsQueryRule; a database may still choose);
// - the standard headers and OpenCV's that its headers included (VINS's
//   files use <fstream>, <list>, <set>, ... without including them).
// Needs Boost's dynamic_bitset and OpenCV's imgproc, as VINS does. Found
// through the opt-in target binbow::dbow2_names (pkg-config
// binbow-dbow2-names).
#ifndef BINBOW_COMPAT_NAMES_VINS_DBOW2_H
#define BINBOW_COMPAT_NAMES_VINS_DBOW2_H

#include <algorithm>
#include <cassert>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <list>
#include <map>
#include <numeric>
#include <opencv2/opencv.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "../DVision/DVision.h"
#include "binbow/compat/DBoW2.h"
#include "binbow/compat/detail/vins_query_rule.h"

#endif
