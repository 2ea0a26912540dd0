// The include name "Thirdparty/DBoW2/DBoW2/TemplatedVocabulary.h" of
// ORB-SLAM's copy of DBoW2: binbow's DBoW2-compatible TemplatedVocabulary,
// with everything the copy's header brought along, which ORB-SLAM2's and
// ORB-SLAM3's own files rely on without including it themselves:
// - `using namespace std;` at global scope (their files write vector,
//   string, ifstream, cout... unqualified);
// - the standard headers it included (<fstream>, <algorithm>, <numeric>,
//   <limits>, <cassert>, <vector>, <string>) and OpenCV's core;
// - its FeatureVector.h and BowVector.h (with <iostream>, and Boost
//   serialization of both vectors wherever Boost's headers are found);
// - DUtils::Random from its ../DUtils/Random.h.
// Upstream DBoW2's header has none of this; the other include names
// (bare, <DBoW2/...>) bring nothing. Found through the opt-in target
// binbow::dbow2_names (pkg-config binbow-dbow2-names).
#ifndef BINBOW_COMPAT_NAMES_ORBSLAM_TEMPLATED_VOCABULARY_H
#define BINBOW_COMPAT_NAMES_ORBSLAM_TEMPLATED_VOCABULARY_H

#include <algorithm>
#include <cassert>
#include <fstream>
#include <limits>
#include <numeric>
#include <opencv2/core/core.hpp>
#include <string>
#include <vector>

#include "../DUtils/Random.h"
#include "BowVector.h"
#include "FeatureVector.h"
#include "binbow/compat/TemplatedVocabulary.h"

using namespace std;

#endif
