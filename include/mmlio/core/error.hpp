#pragma once
#include <stdexcept>
#include <string>

namespace mmlio {

/// An error the user can act on: the message is one line naming what, where and the fix.
/// The CLI prints it as `mmlio: <message>` and exits non-zero.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace mmlio
