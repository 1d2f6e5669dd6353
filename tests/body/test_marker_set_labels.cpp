// Label normalisation: labs spell the same marker differently (case, separators, Left/Right,
// numbered clusters, subject prefixes with or without a separator); each spelling must find its
// marker, and nothing that is not the same marker may.
#include <s2kf/body/label_text.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_labels.hpp>
#include <s2kf/body/marker_set_mapping.hpp>

#include <s2kf/app/marker_set_json.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace {

using namespace s2kf;

body::MarkerSet set_of(const std::vector<std::string>& labels) {
  body::MarkerSet set;
  set.name = "test";
  for (const std::string& label : labels) {
    body::MarkerSetEntry entry;
    entry.label = label;
    entry.like = "C7";
    set.entries.push_back(entry);
  }
  return set;
}

/// The set entry label each recording label was assigned ("" where none).
std::vector<std::string> assigned(const std::vector<std::string>& labels, const body::MarkerSet& set) {
  const body::LabelAssignment a = body::assign_labels(labels, set);
  std::vector<std::string> result;
  for (int e : a.entry_of_label)
    result.push_back(e < 0 ? "" : set.entries[static_cast<std::size_t>(e)].label);
  return result;
}

TEST(LabelNormalisation, CanonicalSpellings) {
  for (const char* spelling : {"LIAS", "L_IAS", "l-ias", "L IAS", "Left_IAS", "Left IAS", "IAS_L", "IAS_Left",
                               "LeftIAS", "Subject:L_IAS", " L_IAS "})
    EXPECT_EQ(canonical_label(spelling), "LIAS") << spelling;
  EXPECT_EQ(canonical_label("RightKnee"), "RKNEE");
  EXPECT_EQ(canonical_label("KneeRight"), "RKNEE");
  EXPECT_EQ(canonical_label("Knee_R"), "RKNEE");
  EXPECT_EQ(canonical_label("LTH_01"), "LTH1");
  EXPECT_EQ(canonical_label("LTH_10"), "LTH10");  // only leading zeros go
  EXPECT_EQ(canonical_label("T10"), "T10");
  EXPECT_EQ(canonical_label("CV7"), "CV7");
  // Not side words: a trailing capital L of a name, an upper-case "LEFT" inside a word.
  EXPECT_EQ(canonical_label("HeadL"), "HEADL");
  EXPECT_EQ(canonical_label("WaistLFront"), "WAISTLFRONT");
  EXPECT_EQ(canonical_label(""), "");
}

TEST(LabelNormalisation, SpellingVariantsFindTheirMarkers) {
  const body::MarkerSet set = set_of({"L_IAS", "R_IAS", "SXS", "LKnee", "LTH1", "LTH2"});
  const std::vector<std::string> labels{"l_ias", "Right-IAS", "sxs", "KneeLeft", "L_TH_01", "LTH_02", "XYZ"};
  EXPECT_EQ(assigned(labels, set),
            (std::vector<std::string>{"L_IAS", "R_IAS", "SXS", "LKnee", "LTH1", "LTH2", ""}));
  const body::LabelAssignment a = body::assign_labels(labels, set);
  EXPECT_EQ(a.rule_of_label[0], body::LabelRule::ignoring_case);
  EXPECT_EQ(a.rule_of_label[1], body::LabelRule::spelling);
  const std::vector<std::string> notes = a.notes(labels, set);
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_EQ(notes[0], "2 label(s) matched ignoring case (l_ias -> L_IAS, sxs -> SXS)");
  EXPECT_EQ(notes[1].rfind("4 label(s) matched ignoring case, separators", 0), 0u) << notes[1];
}

TEST(LabelNormalisation, ExactNamesWinOverSpellingsAndFirstLabelWins) {
  const body::MarkerSet set = set_of({"LIAS", "RIAS"});
  // "L_IAS" comes first but only matches by spelling; the exact "LIAS" takes the marker.
  EXPECT_EQ(assigned({"L_IAS", "LIAS", "RIAS", "rias"}, set),
            (std::vector<std::string>{"", "LIAS", "RIAS", ""}));
  // Two entries of one canonical spelling: a third spelling matches neither.
  const body::MarkerSet ambiguous = set_of({"L_IAS", "LIAS"});
  EXPECT_EQ(assigned({"l-ias"}, ambiguous), (std::vector<std::string>{""}));
}

TEST(LabelNormalisation, SubjectPrefixWithoutSeparator) {
  // Subject "L" labels its markers LLFHD, LRFHD, ..., LL_IAS: the prefix goes only where the rest
  // is a marker of the set.
  const body::MarkerSet set = set_of({"LFHD", "RFHD", "L_IAS", "C7"});
  const std::vector<std::string> labels{"LLFHD", "LRFHD", "LL_IAS", "LC7", "LEXTRA", "LFHD2"};
  EXPECT_EQ(assigned(labels, set), (std::vector<std::string>{"LFHD", "RFHD", "L_IAS", "C7", "", ""}));
  const body::LabelAssignment a = body::assign_labels(labels, set);
  EXPECT_EQ(a.subject_prefix, "L");
  const std::vector<std::string> notes = a.notes(labels, set);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("4 label(s) matched after removing the subject prefix 'L'"), std::string::npos)
      << notes[0];
  // With a separator ("Q_HeadL", the Qualisys skeleton prefix), the longer prefix is reported.
  const body::MarkerSet animation = set_of({"HeadL", "HeadR", "Chest"});
  const body::LabelAssignment q = body::assign_labels({"Q_HeadL", "Q_HeadR", "Q_Chest"}, animation);
  EXPECT_EQ(q.entries_found(), 3);
  EXPECT_EQ(q.subject_prefix, "Q_");
  // A label that is a marker as it stands keeps its name, and one label alone makes no prefix.
  const body::MarkerSet pig = set_of({"LASI", "ASI", "KNE"});
  EXPECT_EQ(assigned({"LASI", "LKNE"}, pig), (std::vector<std::string>{"LASI", ""}));
}

TEST(LabelNormalisation, BundledSetsAcceptPrefixedRecordings) {
  // A Plug-in Gait recording of subject "L" without a colon: every marker found, the summary says how.
  const body::MarkerSet pig =
      app::load_marker_set(std::filesystem::path(S2KF_DATA_DIR) / "markersets" / "plugin_gait.json");
  std::vector<std::string> labels;
  for (const std::string& label : pig.labels()) labels.push_back("L" + label);
  const body::MarkerMapping mapping = body::map_marker_set(labels, pig);
  EXPECT_EQ(mapping.markers_used(), static_cast<int>(pig.entries.size()));
  EXPECT_TRUE(mapping.ignored_labels.empty());
  ASSERT_EQ(mapping.label_notes.size(), 1u);
  EXPECT_NE(mapping.label_notes[0].find("subject prefix 'L'"), std::string::npos);
  EXPECT_DOUBLE_EQ(body::marker_set_match(labels, pig), 1.0);
}

}  // namespace
