/// @file
/// Header-only by default; S2KF_COMPILED opts into one compiled copy of the heavy parts (the rigid
/// fit's SVD, the sample-set optimiser, the tracker's filter instantiation): define it for every
/// file of a target and link the `s2kf::compiled` library, and those parts are compiled once there
/// instead of in every file that includes them. S2KF_INLINE marks their definitions.
#pragma once

#if defined(S2KF_COMPILED) && !defined(S2KF_COMPILING_LIBRARY)
#define S2KF_INLINE
#elif defined(S2KF_COMPILING_LIBRARY)
#define S2KF_INLINE
#else
#define S2KF_INLINE inline
#endif
