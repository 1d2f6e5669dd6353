/// @file
/// The options of `s2kf track` and `s2kf calibrate` that choose the output files (app::OutputSettings).
#pragma once

#include <s2kf/app/extra_outputs.hpp>

#include <CLI/CLI.hpp>

namespace s2kf::cli {

/// --mass: the subject's body mass, which the .osim's segment masses and inertias (de Leva) scale with.
inline void add_mass_option(CLI::App& command, double& body_mass_kg) {
  command
      .add_option("--mass", body_mass_kg,
                  "body mass in kg for the OpenSim model's segment masses and inertias (de Leva 1996; "
                  "default: 24.1 kg/m^2 times the height squared)")
      ->check(CLI::Range(1.0, 500.0));
}

/// Registers the output options on a command.
inline void add_output_options(CLI::App& command, app::OutputSettings& settings) {
  command
      .add_option(
          "--formats", settings.formats,
          "files to write, comma-separated: csv, mot (OpenSim motion), bvh, osim (OpenSim model), trc "
          "(markers for OpenSim), mmm (MMM XML) (default: all)")
      ->delimiter(',')
      ->check(CLI::IsMember(app::known_output_formats()));
  command.add_option("--bvh-units", settings.bvh_units, "BVH length unit: m (Blender's default) or cm")
      ->check(CLI::IsMember({"m", "cm"}));
  command.add_flag("--derivatives", settings.derivatives,
                   "also write PREFIX_vel.csv and PREFIX_acc.csv (finite differences of the motion)");
  add_mass_option(command, settings.body_mass_kg);
}

}  // namespace s2kf::cli
