/// @file
/// Text helpers for names read from files (C3D labels and parameters, marker-set labels): blanks
/// trimmed, case folded (ASCII only: labels are matched byte for byte otherwise), subject prefixes.
#pragma once

#include <cctype>
#include <string>
#include <string_view>

namespace s2kf {

/// `text` without leading and trailing blanks (space, tab, CR, LF and the NUL padding of C3D).
inline std::string trim(std::string_view text) {
  std::size_t begin = 0;
  std::size_t end = text.size();
  const auto blank = [](char c) { return c == ' ' || c == '\0' || c == '\t' || c == '\r' || c == '\n'; };
  while (begin < end && blank(text[begin])) ++begin;
  while (end > begin && blank(text[end - 1])) --end;
  return std::string(text.substr(begin, end - begin));
}

inline std::string upper_case(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

inline std::string lower_case(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

/// True when the two names are equal ignoring ASCII case.
inline bool same_name_ignoring_case(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::toupper(static_cast<unsigned char>(a[i])) != std::toupper(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

/// The label without a subject prefix ("Subject:LASI" -> "LASI") and surrounding blanks.
inline std::string strip_subject_prefix(const std::string& label) {
  const auto colon = label.rfind(':');
  return trim(colon == std::string::npos ? std::string_view(label)
                                         : std::string_view(label).substr(colon + 1));
}

}  // namespace s2kf
