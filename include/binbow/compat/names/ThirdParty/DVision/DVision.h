// The include name "ThirdParty/DVision/DVision.h" of VINS-Mono/Fusion's copy
// of DLib's DVision: its BRIEF extractor (BRIEF.h). Found through the opt-in
// target binbow::dbow2_names (pkg-config binbow-dbow2-names).
#include "BRIEF.h"
