/// @file
/// Numbers as text at the speed the per-frame outputs need: std::to_chars, which the C++ standard
/// defines to give printf's output for the same format and precision (%.*g, %.*f), so the files
/// are byte for byte what `out << std::setprecision(p) << value` wrote, at a fraction of an
/// ostream's cost per number (a tracked frame writes several hundred numbers over its files).
#pragma once

#include <charconv>
#include <iomanip>
#include <ios>
#include <ostream>
#include <system_error>

namespace s2kf::io {

/// `value` as printf("%.*g", significant, value) writes it: the default (general) format of an
/// ostream whose precision is `significant`.
inline void write_general(std::ostream& out, double value, int significant) {
  char text[64];
  const std::to_chars_result end =
      std::to_chars(text, text + sizeof text, value, std::chars_format::general, significant);
  if (end.ec == std::errc{})
    out.write(text, end.ptr - text);
  else  // cannot happen for a double at up to 17 digits; kept as the plain path
    out << std::defaultfloat << std::setprecision(significant) << value;
}

/// `value` as printf("%.*f", decimals, value) writes it (std::fixed); a number too long for the
/// buffer (64 characters: beyond about 1e56) goes through the ostream.
inline void write_fixed(std::ostream& out, double value, int decimals) {
  char text[64];
  const std::to_chars_result end =
      std::to_chars(text, text + sizeof text, value, std::chars_format::fixed, decimals);
  if (end.ec == std::errc{})
    out.write(text, end.ptr - text);
  else
    out << std::fixed << std::setprecision(decimals) << value;
}

}  // namespace s2kf::io
