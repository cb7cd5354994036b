// A technique's options declared once: see options.h.
#include "penumbra/options.h"

#include <charconv>

#include <fmt/format.h>

namespace penumbra::detail {

double decimalDouble(float value) {
  const std::string text = fmt::format("{}", value);  // the shortest form that reads back as `value`
  double out = static_cast<double>(value);
  std::from_chars(text.data(), text.data() + text.size(), out);
  return out;
}

}  // namespace penumbra::detail
