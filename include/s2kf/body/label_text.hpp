/// @file
/// Text helpers for names read from files (C3D labels and parameters, marker-set labels): bytes
/// decoded to UTF-8, blanks trimmed, case folded (ASCII only: labels are matched byte for byte
/// otherwise), subject prefixes, and the canonical spelling that lets `L_IAS`, `l-ias`, `Left IAS`
/// and `LIAS` match.
#pragma once

#include <cctype>
#include <string>
#include <string_view>
#include <vector>

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

/// True when `text` is well-formed UTF-8 (no overlong forms, surrogates or code points past U+10FFFF).
inline bool is_utf8(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
    const unsigned char lead = byte(i);
    std::size_t length = 0;
    unsigned char low = 0x80, high = 0xBF;  // the range of the second byte
    if (lead < 0x80)
      length = 1;
    else if (lead >= 0xC2 && lead <= 0xDF)
      length = 2;
    else if (lead >= 0xE0 && lead <= 0xEF)
      length = 3, low = lead == 0xE0 ? 0xA0 : 0x80, high = lead == 0xED ? 0x9F : 0xBF;
    else if (lead >= 0xF0 && lead <= 0xF4)
      length = 4, low = lead == 0xF0 ? 0x90 : 0x80, high = lead == 0xF4 ? 0x8F : 0xBF;
    else
      return false;
    if (i + length > text.size()) return false;
    for (std::size_t k = 1; k < length; ++k)
      if (byte(i + k) < (k == 1 ? low : 0x80) || byte(i + k) > (k == 1 ? high : 0xBF)) return false;
    i += length;
  }
  return true;
}

/// Text bytes from a file as UTF-8: kept when they already are UTF-8 (ASCII included), else read as
/// Latin-1, the 8-bit text of European C3D files ("\xC9" becomes "\u00C9", É). Every character the
/// file has survives, so labels still match a marker set that spells them the same way.
inline std::string utf8_from_file_text(std::string_view bytes) {
  if (is_utf8(bytes)) return std::string(bytes);
  std::string text;
  text.reserve(2 * bytes.size());
  for (const char c : bytes) {
    const auto code = static_cast<unsigned char>(c);
    if (code < 0x80) {
      text += c;
    } else {
      text += static_cast<char>(0xC0 | (code >> 6));
      text += static_cast<char>(0x80 | (code & 0x3F));
    }
  }
  return text;
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

/// The spelling-free form of a label, for matching labels written differently by different labs:
/// the "Subject:" prefix removed, upper case, the separators `_`, `-`, `.` and blanks dropped, a side
/// word (`Left`/`Right`, as the first word or, CamelCase or separated, as the last: `Knee_L`,
/// `KneeLeft`) written as a leading L/R, and leading zeros of numbers dropped (cluster markers
/// `LTH_01` = `LTH1`). So `L_IAS`, `l-ias`, `Left IAS`, `IAS_L` and `LIAS` are all "LIAS".
inline std::string canonical_label(const std::string& label) {
  const std::string text = strip_subject_prefix(label);
  std::vector<std::string> words;  // split at separators and at a CamelCase "Left"/"Right" ending
  std::string word;
  const auto flush = [&] {
    if (!word.empty()) words.push_back(word);
    word.clear();
  };
  for (char c : text) {
    if (c == '_' || c == '-' || c == '.' || c == ' ' || c == '\t')
      flush();
    else
      word += c;
  }
  flush();
  if (words.empty()) return "";
  for (const char* side : {"Left", "Right"}) {
    std::string& last = words.back();
    const std::string_view s(side);
    if (last.size() > s.size() && last.compare(last.size() - s.size(), s.size(), s) == 0 &&
        std::islower(static_cast<unsigned char>(last[last.size() - s.size() - 1]))) {
      last.erase(last.size() - s.size());
      words.push_back(side);
      break;
    }
  }
  for (std::string& w : words) w = upper_case(w);
  std::string side;
  const auto side_letter = [](const std::string& w) -> std::string {
    if (w == "L" || w == "LEFT") return "L";
    if (w == "R" || w == "RIGHT") return "R";
    return "";
  };
  if (words.size() > 1 && !side_letter(words.back()).empty()) {
    side = side_letter(words.back());
    words.pop_back();
  } else if (words.size() > 1 && (words.front() == "LEFT" || words.front() == "RIGHT")) {
    side = side_letter(words.front());
    words.erase(words.begin());
  } else if (words.front().size() > 5 && words.front().rfind("RIGHT", 0) == 0) {
    side = "R";  // RightKnee
    words.front().erase(0, 5);
  } else if (words.front().size() > 4 && words.front().rfind("LEFT", 0) == 0) {
    side = "L";  // LeftKnee
    words.front().erase(0, 4);
  }
  std::string joined = side;
  for (const std::string& w : words) joined += w;
  std::string result;  // leading zeros of each number dropped
  for (std::size_t i = 0; i < joined.size(); ++i) {
    const bool digit = std::isdigit(static_cast<unsigned char>(joined[i])) != 0;
    const bool starts_number = digit && (i == 0 || !std::isdigit(static_cast<unsigned char>(joined[i - 1])));
    if (starts_number)
      while (joined[i] == '0' && i + 1 < joined.size() &&
             std::isdigit(static_cast<unsigned char>(joined[i + 1])))
        ++i;
    result += joined[i];
  }
  return result;
}

}  // namespace s2kf
