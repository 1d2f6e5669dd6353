/// @file
/// Header-only by default, or one compiled copy of the heavy functions, by the user's choice.
///
/// The tracker, the subject calibration, the session and the evaluation each instantiate the
/// filter's update and hundreds of Eigen kernels; a translation unit that merely included their
/// definitions would spend tens of seconds in the compiler. So every function that is not a
/// template and does more than a line or two is declared in its header `name.hpp` and defined in
/// `name.hxx` beside it (as Pinocchio keeps its algorithms):
///
/// - header-only (the CMake target `s2kf::s2kf`): each header includes its `.hxx` at its end, and
///   the definitions are `inline`;
/// - compiled (`s2kf::compiled`, which defines `S2KF_COMPILED`): headers declare only, and the
///   library `s2kf_compiled` compiles each concept's `.hxx` files once, in `src/<concept>.cpp`
///   (one translation unit per concept folder, the core's in two, so they compile in parallel).
#pragma once

#if defined(S2KF_COMPILED)
#define S2KF_INLINE
#else
#define S2KF_INLINE inline
#endif
