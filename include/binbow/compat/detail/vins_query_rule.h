// DBoW2 compatibility layer: VINS's fork's query rule for the whole program.
// Included by the VINS spellings of the headers (names/ThirdParty/DBoW/):
// code written for VINS's copy of DBoW2 gets its rule (the newest entry is
// a candidate of every L1_NORM query, see
// TemplatedDatabase::setVinsQueryRule) in every database that does not
// choose, however its translation units are ordered. Not meant to be used
// directly.
//
// C++11, standard library only.
#ifndef BINBOW_COMPAT_DBOW2_DETAIL_VINS_QUERY_RULE_H
#define BINBOW_COMPAT_DBOW2_DETAIL_VINS_QUERY_RULE_H

#include "binbow/compat/detail/core.h"

namespace DBoW2 {
namespace binbow_detail {
namespace {
// Set before main() runs, and read by queries only: a database constructed
// during static initialisation still follows it.
const bool vins_query_rule_for_program = select_vins_query_rule();
}  // namespace
}  // namespace binbow_detail
}  // namespace DBoW2

#endif
