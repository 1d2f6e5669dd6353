/// @file
/// The files the viewer page is made of, compiled into the program: CMake generates their
/// definitions (viewer_assets.cpp in the build tree, see embed_assets.cmake) from
/// third_party/three/ and apps/s2kf/viewer/, so the program needs no data files to write a page.
#pragma once

#include <string>

namespace s2kf::cli::viewer {

std::string three_module_source();    ///< third_party/three/three.module.min.js
std::string orbit_controls_source();  ///< third_party/three/OrbitControls.js
std::string three_licence_text();     ///< third_party/three/LICENSE
std::string page_template();          ///< apps/s2kf/viewer/viewer.html
std::string page_style();             ///< apps/s2kf/viewer/viewer.css
std::string page_script();            ///< apps/s2kf/viewer/viewer.js
const char* three_version();          ///< the vendored three.js version, e.g. "0.170.0"

}  // namespace s2kf::cli::viewer
