// s2kf model: the body model's marker positions (zero pose or a given pose) or its joint table, as CSV.
#include <s2kf/app/marker_set_json.hpp>
#include "command.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/body/pose_columns.hpp>

#include <nlohmann/json.hpp>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

using s2kf::cli::UserError;

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream stream(line);
  while (std::getline(stream, field, ',')) {
    const auto first = field.find_first_not_of(" \t\r\"");
    const auto last = field.find_last_not_of(" \t\r\"");
    fields.push_back(first == std::string::npos ? std::string() : field.substr(first, last - first + 1));
  }
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

double parse_number(const std::string& text, const std::string& file, const std::string& column) {
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(value)) throw std::invalid_argument(text);
    return value;
  } catch (const std::exception&) {
    throw UserError(file + ": column " + column + " holds '" + text + "', which is not a finite number");
  }
}

// The tracker's pose CSV: header of pose_column_names(); data row `row` (0-based, blank lines not
// counted) is used. Extra columns are ignored (diagnostics may follow), but every pose column must be there.
s2kf::body::Pose read_pose_csv(const std::string& file, const s2kf::body::BodyModel& model, long row_index) {
  std::ifstream in(file);
  if (!in) throw UserError("cannot open the pose file " + file);
  std::string header_line, row_line;
  if (!std::getline(in, header_line)) throw UserError(file + " is empty; expected a pose CSV with a header");
  long rows_seen = 0;
  bool found = false;
  while (std::getline(in, row_line))
    if (row_line.find_first_not_of(" \t\r") != std::string::npos && rows_seen++ == row_index) {
      found = true;
      break;
    }
  if (!found && rows_seen == 0) throw UserError(file + " has a header but no data row");
  if (!found)
    throw UserError(file + " has " + std::to_string(rows_seen) + " data rows; --row " +
                    std::to_string(row_index) + " is beyond them (0-based)");
  const auto header = split_csv_line(header_line);
  const auto row = split_csv_line(row_line);
  if (row.size() != header.size())
    throw UserError(file + ": the first data row has " + std::to_string(row.size()) +
                    " fields but the header has " + std::to_string(header.size()));
  std::map<std::string, std::size_t> column_of;
  for (std::size_t k = 0; k < header.size(); ++k) column_of.emplace(header[k], k);
  auto value = [&](const std::string& name) {
    const auto it = column_of.find(name);
    if (it == column_of.end())
      throw UserError(file + " has no column " + name + " (a pose CSV needs all pose columns)");
    return parse_number(row[it->second], file, name);
  };
  s2kf::body::Pose pose;
  pose.root_position = {value("root_x"), value("root_y"), value("root_z")};
  pose.root_rpy = {value("root_roll"), value("root_pitch"), value("root_yaw")};
  for (int j = 0; j < model.joint_count(); ++j) pose.joints(j) = value(model.joints[j].name);
  return pose;
}

s2kf::body::Pose read_pose_json(const std::string& file, const s2kf::body::BodyModel& model) {
  std::ifstream in(file);
  if (!in) throw UserError("cannot open the pose file " + file);
  nlohmann::json doc;
  try {
    in >> doc;
  } catch (const nlohmann::json::exception& e) {
    throw UserError(file + " is not valid JSON (" + e.what() + ")");
  }
  if (!doc.is_object()) throw UserError(file + ": a JSON pose must be an object");
  auto triple = [&](const char* key) -> Eigen::Vector3d {
    if (!doc.contains(key)) return Eigen::Vector3d::Zero();
    const auto& v = doc[key];
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
      throw UserError(file + ": " + key + " must be an array of 3 numbers");
    return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
  };
  for (const auto& item : doc.items())
    if (item.key() != "root_position" && item.key() != "root_rpy" && item.key() != "joints")
      throw UserError(file + ": unknown key '" + item.key() + "' (expected root_position, root_rpy, joints)");
  s2kf::body::Pose pose;
  pose.root_position = triple("root_position");
  pose.root_rpy = triple("root_rpy");
  if (doc.contains("joints")) {
    const auto& joints = doc["joints"];
    if (!joints.is_object())
      throw UserError(file + ": joints must be an object of joint name -> angle (rad)");
    for (const auto& item : joints.items()) {
      const int j = model.joint_index(item.key());
      if (j < 0) throw UserError(file + ": unknown joint '" + item.key() + "'");
      if (!item.value().is_number())
        throw UserError(file + ": joint " + item.key() + " must be a number (rad)");
      pose.joints(j) = item.value().get<double>();
    }
  }
  if (!pose.root_position.allFinite() || !pose.root_rpy.allFinite() || !pose.joints.allFinite())
    throw UserError(file + " holds a number that is not finite");
  return pose;
}

// A JSON pose starts with '{'; anything else is read as a pose CSV.
bool looks_like_json(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw UserError("cannot open the pose file " + file);
  char c = 0;
  while (in.get(c))
    if (!std::isspace(static_cast<unsigned char>(c))) return c == '{';
  return false;
}

}  // namespace

static s2kf::cli::RegisterCommand reg{
    "model",
    "Print the body model: marker positions (CSV marker,x,y,z in mm) or, with --joints, the joint table",
    [](CLI::App& app) {
      struct Options {
        double height = 1750;
        std::string subject_file;
        std::string pose_file;
        long row = 0;
        bool joints = false;
      };
      auto options = std::make_shared<Options>();
      CLI::Option* height_option = app.add_option(
          "--height", options->height,
          "Subject height in mm (every length scales with it; default 1750, or the subject file's)");
      app.add_option(
          "--subject", options->subject_file,
          "a subject file (s2kf calibrate), a marker-set file or a bundled set's name: its markers, "
          "bone lengths and joint limits (the model s2kf track --subject tracks with)");
      app.add_option(
          "--pose", options->pose_file,
          "Pose file: a pose CSV (header frame,time,root_x,...,root_yaw,BPx,...; the row --row names) or "
          "JSON {\"root_position\":[x,y,z],\"root_rpy\":[r,p,y],\"joints\":{\"BPx\":...}} (rad)");
      app.add_option("--row", options->row, "with a pose CSV: the data row to use (0-based, default 0)")
          ->check(CLI::NonNegativeNumber);
      app.add_flag(
          "--joints", options->joints,
          "Print the joint table (joint,parent,axis,lower,upper,offset_x,offset_y,offset_z) instead of "
          "the markers");
      app.callback([options, height_option] {
        if (!(options->height > 0) || !std::isfinite(options->height))
          throw UserError("--height must be a positive number of millimetres, got " +
                          std::to_string(options->height));
        // With a subject: the model as s2kf track --subject builds it (session.hpp's prepare_session).
        s2kf::body::BodyModel model;
        if (options->subject_file.empty()) {
          model = s2kf::body::mmm_body_model(options->height);
        } else {
          const s2kf::body::MarkerSet set = s2kf::cli::resolve_marker_set(options->subject_file);
          const s2kf::body::BodyModel base = s2kf::body::mmm_body_model(set.reference_height_mm);
          const double height =
              height_option->count() > 0 ? options->height : set.height_mm.value_or(options->height);
          try {
            model = s2kf::body::apply_marker_set(base, set).scaled(height);
          } catch (const std::invalid_argument& e) {
            throw UserError(options->subject_file + ": " + e.what());
          }
        }
        if (options->joints) {
          if (!options->pose_file.empty())
            throw UserError("--joints prints the joint table; it takes no --pose");
          std::printf("joint,parent,axis,lower,upper,offset_x,offset_y,offset_z\n");
          for (const auto& joint : model.joints)
            std::printf("%s,%s,%c,%.6f,%.6f,%.6f,%.6f,%.6f\n", joint.name.c_str(),
                        model.frame_name(joint.parent_frame).c_str(), s2kf::body::axis_letter(joint.axis),
                        joint.lower, joint.upper, joint.translation.x(), joint.translation.y(),
                        joint.translation.z());
          return;
        }
        s2kf::body::Pose pose;
        if (!options->pose_file.empty())
          pose = looks_like_json(options->pose_file) ? read_pose_json(options->pose_file, model)
                                                     : read_pose_csv(options->pose_file, model, options->row);
        const Eigen::Matrix3Xd markers = s2kf::body::marker_positions(model, pose);
        std::printf("marker,x,y,z\n");
        for (int m = 0; m < model.marker_count(); ++m)
          std::printf("%s,%.6f,%.6f,%.6f\n", model.markers[m].name.c_str(), markers(0, m), markers(1, m),
                      markers(2, m));
      });
    }};
