// Argument helpers shared by the bench tools (bench-only header).
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace meso::bench {

// "a,b,,c" -> {"a", "b", "c"}: a comma-separated list, empty items dropped.
inline std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace meso::bench
