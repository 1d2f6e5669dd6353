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

namespace detail {

/// `value` in `format` at `precision`, through std::to_chars. A number too long for the buffer (64
/// characters: fixed notation beyond about 1e56) goes through the ostream, whose format flags and
/// precision are put back afterwards, so the caller's later numbers are not affected.
inline void write_number(std::ostream& out, double value, std::chars_format format, int precision) {
  char text[64];
  const std::to_chars_result end = std::to_chars(text, text + sizeof text, value, format, precision);
  if (end.ec == std::errc{}) {
    out.write(text, end.ptr - text);
    return;
  }
  const std::ios_base::fmtflags flags = out.flags();
  const std::streamsize old_precision = out.precision();
  out.setf(format == std::chars_format::fixed ? std::ios_base::fixed : std::ios_base::fmtflags{},
           std::ios_base::floatfield);
  out << std::setprecision(precision) << value;
  out.flags(flags);
  out.precision(old_precision);
}

}  // namespace detail

/// `value` as printf("%.*g", significant, value) writes it: the default (general) format of an
/// ostream whose precision is `significant`.
inline void write_general(std::ostream& out, double value, int significant) {
  detail::write_number(out, value, std::chars_format::general, significant);
}

/// `value` as printf("%.*f", decimals, value) writes it (std::fixed).
inline void write_fixed(std::ostream& out, double value, int decimals) {
  detail::write_number(out, value, std::chars_format::fixed, decimals);
}

}  // namespace s2kf::io
