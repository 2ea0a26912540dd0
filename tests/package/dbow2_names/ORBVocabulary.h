// Written as ORB-SLAM2/3's include/ORBVocabulary.h is: the copy of DBoW2's
// headers by their Thirdparty/ paths, and the ORBVocabulary typedef.
#ifndef BINBOW_PACKAGE_DBOW2_NAMES_ORB_VOCABULARY_H
#define BINBOW_PACKAGE_DBOW2_NAMES_ORB_VOCABULARY_H

#include "Thirdparty/DBoW2/DBoW2/FORB.h"
#include "Thirdparty/DBoW2/DBoW2/TemplatedVocabulary.h"

typedef DBoW2::TemplatedVocabulary<DBoW2::FORB::TDescriptor, DBoW2::FORB> ORBVocabulary;

#endif
