// Problems that do not make an operation fail (binbow::set_warning_handler).
#pragma once

#include <string>

namespace binbow::detail {

// Passes `message` to the warning handler (by default: stderr).
void warn(const std::string& message) noexcept;

}  // namespace binbow::detail
