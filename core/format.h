// Numbers in messages: a double printed with 17 significant digits, so that a value a message names is the
// exact value that was checked (a limit crossed by 1e-12 shows the crossing).
#pragma once
#include <sstream>
#include <string>

namespace stex {

inline std::string exact_number(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

}  // namespace stex
