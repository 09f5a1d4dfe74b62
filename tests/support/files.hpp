#pragma once
// Small file helpers for tests that check what a tool wrote.
#include <fstream>
#include <sstream>
#include <string>

namespace test_support {

// The whole file ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace test_support
