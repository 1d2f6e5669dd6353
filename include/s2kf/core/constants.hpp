/// @file
/// Mathematical constants every part of s2kf shares (C++17 has no std::numbers).
#pragma once

namespace s2kf {

/// pi to double precision; 2 * kPi is exactly the double nearest to 2 pi.
inline constexpr double kPi = 3.14159265358979323846;
/// Degrees per radian.
inline constexpr double kDegreesPerRadian = 180.0 / kPi;

}  // namespace s2kf
