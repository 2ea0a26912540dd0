// The include name "ThirdParty/DBoW/BowVector.h" of VINS-Mono/Fusion's copy of
// DBoW2: the whole of the copy's API as its DBoW2.h gives it (see there),
// since VINS's files include this one beside DBoW2.h. Found through the
// opt-in target binbow::dbow2_names (pkg-config binbow-dbow2-names).
#include "DBoW2.h"
