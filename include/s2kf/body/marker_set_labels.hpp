/// @file
/// Which recording label is which marker of a set, when labs spell the labels differently: exact
/// names first, then ignoring case, then the canonical spelling (separators, Left/Right, leading
/// zeros: canonical_label), then with a subject prefix removed that has no separator ("LRFHD" of
/// subject "L"). Every rule after the first is reported, so the summary can say what was done.
#pragma once

#include <s2kf/body/label_text.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/core/compilation_mode.hpp>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

namespace s2kf::body {

/// How a recording label found its marker.
enum class LabelRule { none, exact, ignoring_case, spelling, subject_prefix };

/// The outcome of assign_labels.
struct LabelAssignment {
  std::vector<int> entry_of_label;       ///< per recording label: the set entry it feeds, or -1
  std::vector<LabelRule> rule_of_label;  ///< per recording label: how (none where -1)
  std::string subject_prefix;            ///< removed from the labels matched by LabelRule::subject_prefix

  int entries_found() const {
    return static_cast<int>(
        std::count_if(entry_of_label.begin(), entry_of_label.end(), [](int e) { return e >= 0; }));
  }

  /// One sentence per rule beyond exact matching, with up to three examples ("label -> marker").
  std::vector<std::string> notes(const std::vector<std::string>& recording_labels,
                                 const MarkerSet& set) const {
    std::vector<std::string> result;
    const auto describe = [&](LabelRule rule, const std::string& what) {
      int count = 0;
      std::string examples;
      for (std::size_t p = 0; p < entry_of_label.size(); ++p) {
        if (rule_of_label[p] != rule) continue;
        if (++count <= 3)
          examples += (examples.empty() ? "" : ", ") + recording_labels[p] + " -> " +
                      set.entries[static_cast<std::size_t>(entry_of_label[p])].label;
      }
      if (count > 0)
        result.push_back(std::to_string(count) + " label(s) matched " + what + " (" + examples +
                         (count > 3 ? ", ..." : "") + ")");
    };
    describe(LabelRule::ignoring_case, "ignoring case");
    describe(LabelRule::spelling, "ignoring case, separators, Left/Right spelling and leading zeros");
    describe(LabelRule::subject_prefix, "after removing the subject prefix '" + subject_prefix + "'");
    return result;
  }
};

namespace label_detail {

/// Every name of every entry under `key_of(name)`; a key two entries share maps to -2 (ambiguous:
/// never matched by that rule).
template <typename KeyOf>
std::map<std::string, int> entry_keys(const MarkerSet& set, KeyOf key_of) {
  std::map<std::string, int> keys;
  for (std::size_t e = 0; e < set.entries.size(); ++e) {
    std::vector<std::string> names{set.entries[e].label};
    names.insert(names.end(), set.entries[e].aliases.begin(), set.entries[e].aliases.end());
    for (const std::string& name : names) {
      const std::string key = key_of(name);
      if (key.empty()) continue;
      const auto [it, inserted] = keys.emplace(key, static_cast<int>(e));
      if (!inserted && it->second != static_cast<int>(e)) it->second = -2;
    }
  }
  return keys;
}

}  // namespace label_detail

/// Assigns recording labels to the set's entries, rule by rule: a label is matched by the first
/// rule that finds a free entry for it, and within a rule the first label takes an entry (a second
/// label for the same marker stays unassigned). A subject prefix without a separator is removed
/// only where the rest then matches an entry, and only when at least two labels agree on it.
LabelAssignment assign_labels(const std::vector<std::string>& recording_labels, const MarkerSet& set);

/// How well a recording's labels fit a set: the fraction of the set's markers that assign_labels
/// finds among the labels.
double marker_set_match(const std::vector<std::string>& recording_labels, const MarkerSet& set);

}  // namespace s2kf::body

#if !defined(S2KF_COMPILED)
#include <s2kf/body/marker_set_labels.hxx>
#endif
