// The detector's typedefs, written as DLoopDetector's DLoopDetector.h is:
// "DBoW2.h" and "FORB.h" by their bare names.
#ifndef BINBOW_PACKAGE_DBOW2_NAMES_PLACE_DETECTOR_H
#define BINBOW_PACKAGE_DBOW2_NAMES_PLACE_DETECTOR_H

#include "DBoW2.h"
#include "FORB.h"
#include "TemplatedPlaceDetector.h"

typedef TemplatedPlaceDetector<DBoW2::FORB::TDescriptor, DBoW2::FORB> OrbPlaceDetector;

#endif
