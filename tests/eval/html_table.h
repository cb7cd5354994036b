// Reads the report page's results table back (src/eval/html_report.cpp writes one
// <tr data-technique="..."> per row and the exact JSON value of each cell in <td data-value="...">),
// so tests can compare the page with compare.json.
#pragma once

#include <map>
#include <regex>
#include <string>
#include <vector>

namespace penumbra::testing {

// technique label -> the data-value of each cell of its row, in column order.
inline std::map<std::string, std::vector<std::string>> htmlTableValues(const std::string& html) {
  std::map<std::string, std::vector<std::string>> out;
  const std::regex rowRe("<tr data-technique=\"([^\"]*)\">(.*?)</tr>");
  const std::regex cellRe("<td data-value=\"([^\"]*)\">");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), rowRe); it != std::sregex_iterator(); ++it) {
    const std::string cells = (*it)[2];
    auto& values = out[(*it)[1]];
    for (auto c = std::sregex_iterator(cells.begin(), cells.end(), cellRe); c != std::sregex_iterator(); ++c)
      values.push_back((*c)[1]);
  }
  return out;
}

}  // namespace penumbra::testing
