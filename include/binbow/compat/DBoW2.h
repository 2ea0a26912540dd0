// binbow's DBoW2-compatible API: code written against DBoW2 (ORB-SLAM2/3,
// DLoopDetector, VINS, ...) builds against binbow by including this header
// instead of DBoW2's "DBoW2/DBoW2.h" (or the header of the same name under
// binbow/compat/ instead of DBoW2's BowVector.h, FORB.h, ...), and linking
// the CMake target binbow::dbow2.
//
// C++11: these headers include only the standard library and OpenCV core;
// the implementation is compiled inside binbow over binbow::Vocabulary and
// binbow::Database. What is covered and what differs: docs/dbow2-compat.md.
#ifndef BINBOW_COMPAT_DBOW2_DBOW2_H
#define BINBOW_COMPAT_DBOW2_DBOW2_H

#include "binbow/compat/BowVector.h"
#include "binbow/compat/FBrief.h"
#include "binbow/compat/FORB.h"
#include "binbow/compat/FeatureVector.h"
#include "binbow/compat/QueryResults.h"
#include "binbow/compat/TemplatedDatabase.h"
#include "binbow/compat/TemplatedVocabulary.h"

namespace DBoW2 {
typedef TemplatedVocabulary<FORB::TDescriptor, FORB> OrbVocabulary;
typedef TemplatedDatabase<FORB::TDescriptor, FORB> OrbDatabase;
typedef TemplatedVocabulary<FBrief::TDescriptor, FBrief> BriefVocabulary;
typedef TemplatedDatabase<FBrief::TDescriptor, FBrief> BriefDatabase;
}  // namespace DBoW2

// DBoW2 declares these at global scope.
typedef DBoW2::TemplatedVocabulary<DBoW2::FORB::TDescriptor, DBoW2::FORB> OrbVocabulary;
typedef DBoW2::TemplatedDatabase<DBoW2::FORB::TDescriptor, DBoW2::FORB> OrbDatabase;
typedef DBoW2::TemplatedVocabulary<DBoW2::FBrief::TDescriptor, DBoW2::FBrief> BriefVocabulary;
typedef DBoW2::TemplatedDatabase<DBoW2::FBrief::TDescriptor, DBoW2::FBrief> BriefDatabase;

#endif
