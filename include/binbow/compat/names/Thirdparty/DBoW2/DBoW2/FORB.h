// The include name "Thirdparty/DBoW2/DBoW2/FORB.h" of ORB-SLAM's copy of
// DBoW2: binbow's DBoW2-compatible FORB, with what the copy's header brought
// along: OpenCV's <opencv2/core/core.hpp>, <vector> and <string>. Found
// through the opt-in target binbow::dbow2_names (pkg-config
// binbow-dbow2-names).
#ifndef BINBOW_COMPAT_NAMES_ORBSLAM_FORB_H
#define BINBOW_COMPAT_NAMES_ORBSLAM_FORB_H

#include <opencv2/core/core.hpp>
#include <string>
#include <vector>

#include "binbow/compat/FORB.h"

#endif
