// What the examples share: their command line (--name value pairs) and how they print a vector.
#pragma once

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace examples {

// --name value pairs, each name one of those the example takes. ok() is false once a name was
// not among them, had no value, or had a value its getter could not read: the example then
// prints its usage.
class Options {
 public:
  Options(int argc, char** argv, std::initializer_list<std::string_view> names) {
    for (int i = 1; i < argc && ok_; i += 2) {
      const std::string_view name = argv[i];
      ok_ = i + 1 < argc && std::find(names.begin(), names.end(), name) != names.end();
      if (ok_) values_[std::string(name)] = argv[i + 1];
    }
  }
  bool ok() const { return ok_; }

  std::string text(const std::string& name, std::string fallback = "") const {
    const auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
  }
  double number(const std::string& name, double fallback) {
    const auto it = values_.find(name);
    return it == values_.end() ? fallback : read(it->second);
  }
  // "x,y,z"
  std::vector<double> numbers(const std::string& name, std::vector<double> fallback = {}) {
    const auto it = values_.find(name);
    if (it == values_.end()) return fallback;
    std::vector<double> out;
    std::stringstream in(it->second);
    for (std::string item; std::getline(in, item, ',');) out.push_back(read(item));
    return out;
  }

 private:
  // The whole text a number, or ok() false.
  double read(const std::string& text) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    ok_ = ok_ && !text.empty() && end == text.c_str() + text.size();
    return v;
  }

  std::map<std::string, std::string> values_;
  bool ok_ = true;
};

// [a, b, c], each number with `decimals` places (-1: as %g prints it).
inline std::string format(const std::vector<double>& v, int decimals = -1) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) {
    char buf[32];
    if (decimals < 0) {
      std::snprintf(buf, sizeof buf, "%g", v[i]);
    } else {
      std::snprintf(buf, sizeof buf, "%.*f", decimals, v[i]);
    }
    s += (i ? ", " : "") + std::string(buf);
  }
  return s + "]";
}

}  // namespace examples
