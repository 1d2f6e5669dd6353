/// @file
/// Which instruction set the hot kernels (the product tiles: the moments' float products, the
/// filter's double rank updates, sample draw and bordered Cholesky; batched forward kinematics) run
/// with: each is compiled for SSE2, AVX2 + FMA and AVX-512 (GCC/Clang `target` attributes on x86-64)
/// and the best one the processor has is chosen at run time, so a portable binary runs as fast as
/// one built with -march=native. S2KF_SIMD=sse2|avx2|avx512 forces a variant (measurements, tests).
#pragma once

#include <atomic>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <type_traits>

// x86-64 with GCC or Clang: several variants and a run-time choice; elsewhere one variant, compiled
// for whatever the compiler's flags allow.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(S2KF_NO_DISPATCH)
#define S2KF_DISPATCH 1
#define S2KF_ALWAYS_INLINE inline __attribute__((always_inline))
#define S2KF_ALWAYS_INLINE_LAMBDA __attribute__((always_inline))
#define S2KF_TARGET_AVX2 __attribute__((target("avx2,fma")))
#if defined(__clang__)
#define S2KF_TARGET_AVX512 __attribute__((target("avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")))
#else
// GCC otherwise vectorises plain loops at 256 bits in AVX-512 code (its generic tuning).
#define S2KF_TARGET_AVX512 \
  __attribute__((target("avx512f,avx512vl,avx512dq,avx512bw,avx2,fma,prefer-vector-width=512")))
#endif
#else
#define S2KF_DISPATCH 0
#define S2KF_ALWAYS_INLINE inline
#define S2KF_ALWAYS_INLINE_LAMBDA
#endif

namespace s2kf {

/// The kernel variants, from the oldest x86-64 instruction set to the newest.
enum class InstructionSet { sse2 = 0, avx2 = 1, avx512 = 2 };

inline const char* instruction_set_name(InstructionSet set) {
  switch (set) {
    case InstructionSet::sse2:
      return "sse2";
    case InstructionSet::avx2:
      return "avx2";
    case InstructionSet::avx512:
      return "avx512";
  }
  return "unknown";
}

/// The instruction set the compiler's own flags give every function (the baseline variant).
constexpr InstructionSet compiled_instruction_set() {
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512DQ__) && defined(__AVX512BW__)
  return InstructionSet::avx512;
#elif defined(__AVX2__) && defined(__FMA__)
  return InstructionSet::avx2;
#else
  return InstructionSet::sse2;
#endif
}

/// The best variant this processor runs (never below the compiled baseline).
inline InstructionSet supported_instruction_set() {
#if S2KF_DISPATCH
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw"))
    return InstructionSet::avx512;
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return InstructionSet::avx2;
#endif
  return compiled_instruction_set();
}

/// Throws unless `set` runs here: on this processor, and not below the compiled baseline.
inline void check_instruction_set(InstructionSet set, const std::string& asked_as) {
  const InstructionSet supported = supported_instruction_set();
  if (set > supported)
    throw std::invalid_argument(asked_as + ": this processor runs at most " +
                                instruction_set_name(supported));
  if (set < compiled_instruction_set())
    throw std::invalid_argument(asked_as + ": this build is compiled for " +
                                instruction_set_name(compiled_instruction_set()) + " at least");
}

/// The variant for `forced` (the value of S2KF_SIMD, or null): the supported one unless forced; a
/// forced variant that does not run here (check_instruction_set), or an unknown name, is an error.
inline InstructionSet choose_instruction_set(const char* forced) {
  if (forced == nullptr || *forced == '\0') return supported_instruction_set();
  const std::string name(forced);
  InstructionSet wanted;
  if (name == "sse2")
    wanted = InstructionSet::sse2;
  else if (name == "avx2")
    wanted = InstructionSet::avx2;
  else if (name == "avx512")
    wanted = InstructionSet::avx512;
  else
    throw std::invalid_argument("S2KF_SIMD=" + name + " is not a kernel variant (sse2, avx2 or avx512)");
  check_instruction_set(wanted, "S2KF_SIMD=" + name);
  return wanted;
}

namespace instruction_set_detail {
/// The variant in use, -1 until the first kernel asks (one per process, shared by every thread).
inline std::atomic<int>& chosen() {
  static std::atomic<int> set{-1};
  return set;
}
}  // namespace instruction_set_detail

/// The variant the kernels run: S2KF_SIMD if set, else the best supported; chosen at the first call.
inline InstructionSet active_instruction_set() {
  int set = instruction_set_detail::chosen().load(std::memory_order_relaxed);
  if (set < 0) {
    set = static_cast<int>(choose_instruction_set(std::getenv("S2KF_SIMD")));
    instruction_set_detail::chosen().store(set, std::memory_order_relaxed);
  }
  return static_cast<InstructionSet>(set);
}

/// Runs the kernels with `set` from now on (tests comparing the variants, measurements); throws
/// where it does not run here. Not meant for use while other threads are inside a kernel.
inline void use_instruction_set(InstructionSet set) {
  check_instruction_set(set, std::string("instruction set ") + instruction_set_name(set));
  instruction_set_detail::chosen().store(static_cast<int>(set), std::memory_order_relaxed);
}

/// One phrase for `s2kf --version` and `--verbose`: the variant that runs, why, and the baseline the
/// rest of the code is compiled for, e.g. "kernels avx2 (the best this processor runs; baseline sse2)".
inline std::string instruction_set_text() {
  const char* forced = std::getenv("S2KF_SIMD");
  return std::string("kernels ") + instruction_set_name(active_instruction_set()) +
         (forced != nullptr && *forced != '\0' ? " (forced by S2KF_SIMD" : " (the best this processor runs") +
         "; baseline " + instruction_set_name(compiled_instruction_set()) + ")";
}

/// The instruction set of a variant as a type, for the sizes that depend on it (registers).
template <InstructionSet Set>
using InstructionSetTag = std::integral_constant<InstructionSet, Set>;

/// Calls `body(InstructionSetTag<S>{})` compiled for instruction set S = `set` (or the compiled
/// baseline, where that is higher). `body` and everything it calls must be S2KF_ALWAYS_INLINE
/// (plain loops, no Eigen expressions, whose packet size is fixed by the compiler's flags), so that
/// the whole of it is generated anew in each variant.
template <typename Body>
void run_with_instruction_set(InstructionSet set, Body&& body);

namespace instruction_set_detail {
#if S2KF_DISPATCH
template <typename Body>
S2KF_TARGET_AVX512 void run_avx512(Body& body) {
  body(InstructionSetTag<InstructionSet::avx512>{});
}
template <typename Body>
S2KF_TARGET_AVX2 void run_avx2(Body& body) {
  body(InstructionSetTag<InstructionSet::avx2>{});
}
#endif
template <typename Body>
void run_baseline(Body& body) {
  body(InstructionSetTag<compiled_instruction_set()>{});
}
}  // namespace instruction_set_detail

template <typename Body>
void run_with_instruction_set(InstructionSet set, Body&& body) {
#if S2KF_DISPATCH
  if (set == InstructionSet::avx512 && compiled_instruction_set() < InstructionSet::avx512)
    instruction_set_detail::run_avx512(body);
  else if (set == InstructionSet::avx2 && compiled_instruction_set() < InstructionSet::avx2)
    instruction_set_detail::run_avx2(body);
  else
    instruction_set_detail::run_baseline(body);
#else
  (void)set;
  instruction_set_detail::run_baseline(body);
#endif
}

}  // namespace s2kf
