#pragma once
// Numbers in messages: as a stream prints them with a few significant digits (0.0123, 45.7, 1.2e+03).
#include <sstream>
#include <string>

namespace mmlio {

inline std::string shortNumber(double v, int significant_digits = 3) {
  std::ostringstream os;
  os.precision(significant_digits);
  os << v;
  return os.str();
}

}  // namespace mmlio
