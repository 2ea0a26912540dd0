// Natural ("human") order of file names: digit runs compare as numbers.
#pragma once

#include <string>

namespace binbow::vision {

// True when `a` sorts before `b` in natural order: "2.jpg" < "10.jpg",
// "frame9" < "frame10"; letters compare case-insensitively, then exactly, so
// the order is total and deterministic. Numbers of any length are compared
// without overflow; "007" and "7" are equal as numbers and then ordered by
// their text.
bool natural_less(const std::string& a, const std::string& b);

}  // namespace binbow::vision
