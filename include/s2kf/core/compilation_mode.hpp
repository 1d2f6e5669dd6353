/// @file
/// Header-only by default, or one compiled copy of the heavy functions, by the user's choice.
///
/// The tracker, the subject calibration, the baseline, the smoother and the session each
/// instantiate the filter's update and hundreds of Eigen kernels; a translation unit that merely
/// includes them spends 20-40 s in the compiler, because C++ instantiates every template an inline
/// body uses, called or not, and the many small functions around them (kinematics, charts, files)
/// add up the same way. Every function that is not a template and does more than a line or two is
/// therefore declared where it belongs and defined under `#if S2KF_DEFINE_HEAVY` at the end of its
/// header:
///
/// - default (header-only): the definitions are `inline` and every translation unit sees them;
/// - `S2KF_COMPILED` (the CMake target `s2kf::compiled` sets it): translation units see the
///   declarations only and link the one compiled copy in the `s2kf_compiled` library;
/// - `S2KF_BUILDING_COMPILED`: the one source file of that library, which emits every definition
///   once (non-inline).
#pragma once

#if defined(S2KF_BUILDING_COMPILED)
#define S2KF_DEFINE_HEAVY 1
#define S2KF_INLINE
#elif defined(S2KF_COMPILED)
#define S2KF_DEFINE_HEAVY 0
#define S2KF_INLINE inline
#else
#define S2KF_DEFINE_HEAVY 1
#define S2KF_INLINE inline
#endif
