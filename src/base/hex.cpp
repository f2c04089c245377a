#include "base/hex.h"

namespace hapticd::base {

std::string hex(std::uint64_t value, int digits, HexCase letters) {
  const char* const set = letters == HexCase::kUpper ? "0123456789ABCDEF" : "0123456789abcdef";
  std::string reversed;
  do {
    reversed.push_back(set[value & 0xFu]);
    value >>= 4;
  } while (value != 0 || static_cast<int>(reversed.size()) < digits);
  reversed += "x0";
  return {reversed.rbegin(), reversed.rend()};
}

}  // namespace hapticd::base
