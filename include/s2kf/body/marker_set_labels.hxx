/// @file
/// The definitions of <s2kf/body/marker_set_labels.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/body/marker_set_labels.hpp>

namespace s2kf::body {

S2KF_INLINE LabelAssignment assign_labels(const std::vector<std::string>& recording_labels,
                                          const MarkerSet& set) {
  LabelAssignment result;
  const std::size_t n = recording_labels.size();
  result.entry_of_label.assign(n, -1);
  result.rule_of_label.assign(n, LabelRule::none);
  std::vector<bool> taken(set.entries.size(), false);
  std::vector<std::string> names(n);
  for (std::size_t p = 0; p < n; ++p) names[p] = strip_subject_prefix(recording_labels[p]);

  const auto run_rule = [&](LabelRule rule, const std::map<std::string, int>& keys, auto key_of) {
    for (std::size_t p = 0; p < n; ++p) {
      if (result.entry_of_label[p] >= 0 || names[p].empty()) continue;
      const auto found = keys.find(key_of(names[p]));
      if (found == keys.end() || found->second < 0 || taken[static_cast<std::size_t>(found->second)])
        continue;
      result.entry_of_label[p] = found->second;
      result.rule_of_label[p] = rule;
      taken[static_cast<std::size_t>(found->second)] = true;
    }
  };
  const auto same = [](const std::string& s) { return s; };
  run_rule(LabelRule::exact, label_detail::entry_keys(set, same), same);
  const auto folded = [](const std::string& s) { return upper_case(s); };
  run_rule(LabelRule::ignoring_case, label_detail::entry_keys(set, folded), folded);
  const std::map<std::string, int> canonical_keys = label_detail::entry_keys(set, canonical_label);
  run_rule(LabelRule::spelling, canonical_keys, canonical_label);

  // The prefix (up to 12 characters) that the most unmatched labels carry before a set's name.
  std::map<std::string, int> votes;
  for (std::size_t p = 0; p < n; ++p) {
    if (result.entry_of_label[p] >= 0) continue;
    for (std::size_t k = 1; k < names[p].size() && k <= 12; ++k) {
      const auto found = canonical_keys.find(canonical_label(names[p].substr(k)));
      if (found != canonical_keys.end() && found->second >= 0) ++votes[names[p].substr(0, k)];
    }
  }
  std::string prefix;
  int best = 1;  // a prefix needs at least two labels
  for (const auto& [candidate, count] : votes)
    if (count > best || (count == best && !prefix.empty() && candidate.size() > prefix.size())) {
      prefix = candidate;
      best = count;
    }
  if (!prefix.empty()) {
    const auto without_prefix = [&prefix](const std::string& s) {
      return s.size() > prefix.size() && s.compare(0, prefix.size(), prefix) == 0
                 ? canonical_label(s.substr(prefix.size()))
                 : std::string();
    };
    run_rule(LabelRule::subject_prefix, canonical_keys, without_prefix);
    result.subject_prefix = prefix;
  }
  return result;
}

S2KF_INLINE double marker_set_match(const std::vector<std::string>& recording_labels, const MarkerSet& set) {
  if (set.entries.empty()) return 0.0;
  return static_cast<double>(assign_labels(recording_labels, set).entries_found()) /
         static_cast<double>(set.entries.size());
}

}  // namespace s2kf::body
