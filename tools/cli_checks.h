// Option checks of the CLI with one clear line each: CLI11's PositiveNumber and NonNegativeNumber
// let NaN through and print the double's maximum (309 digits) in their message.
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

namespace tools {

// A finite number > 0 (or >= 0 with `zero_ok`), `unit` named in the message ("s", "mm", ...).
inline CLI::Validator FiniteNumber(bool zero_ok, const std::string& unit = "") {
  const std::string what = std::string("a finite number ") + (zero_ok ? ">= 0" : "> 0") +
                           (unit.empty() ? "" : " (" + unit + ")");
  return CLI::Validator(
      [what, zero_ok](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) || v < 0 ||
            (!zero_ok && v == 0))
          return "expected " + what + ", got " + (text.empty() ? "''" : text);
        return "";
      },
      zero_ok ? "NUMBER >= 0" : "NUMBER > 0");
}
inline CLI::Validator FinitePositive(const std::string& unit = "") {
  return FiniteNumber(false, unit);
}
inline CLI::Validator FiniteNonNegative(const std::string& unit = "") {
  return FiniteNumber(true, unit);
}

// A finite number in [lo, hi], `unit` named in the message.
inline CLI::Validator FiniteInRange(double lo, double hi, const std::string& unit) {
  const std::string what = "a finite number in [" + CLI::detail::to_string(lo) + ", " +
                           CLI::detail::to_string(hi) + "] (" + unit + ")";
  return CLI::Validator(
      [what, lo, hi](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !(v >= lo && v <= hi))
          return "expected " + what + ", got " + (text.empty() ? "''" : text);
        return "";
      },
      "NUMBER");
}

// A whole number >= 0.
inline CLI::Validator WholeNonNegative() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        long long v = 0;
        if (!CLI::detail::lexical_cast(text, v) || v < 0)
          return "expected a whole number >= 0, got " + text;
        return "";
      },
      "INT >= 0");
}

}  // namespace tools
