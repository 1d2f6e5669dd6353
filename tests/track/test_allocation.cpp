// The tracking step allocates nothing after warm-up: every heap allocation of this program (malloc
// and friends, so Eigen's matrices as well as operator new) is counted while frames are processed.
//
// Under AddressSanitizer the allocator belongs to the sanitizer, so only operator new is replaced
// (and counted) there, as tests/body does; the full malloc count runs in the ordinary builds.
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/track/tracker.hpp>

#include "tracker_samples.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <new>
#include <string>
#include <vector>

#include "address_sanitizer.hpp"

namespace {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
void count_allocation() {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

#if !defined(S2KF_TEST_UNDER_ASAN) && defined(__GLIBC__)
#define S2KF_COUNTS_MALLOC 1
// glibc lets a program replace malloc; these forward to its own implementation.
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t size) {
  count_allocation();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  count_allocation();
  return __libc_calloc(count, size);
}
void* realloc(void* p, std::size_t size) {
  count_allocation();
  return __libc_realloc(p, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  count_allocation();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  count_allocation();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  count_allocation();
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) return 12;  // ENOMEM
  *out = p;
  return 0;
}
void free(void* p) { __libc_free(p); }
}
#else
// The replacements pair malloc with free; GCC cannot see that through the inlined operators.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t size) {
  count_allocation();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
// The nothrow form too (std::stable_sort's temporary buffer uses it): left to the sanitizer, its
// memory would come from the sanitizer's operator new and go back through this operator delete.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  count_allocation();
  return std::malloc(size == 0 ? 1 : size);
}
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
#endif

namespace {

using namespace s2kf;
using Visible = Eigen::Array<bool, Eigen::Dynamic, 1>;

long allocations_in(const std::function<void()>& f) {
  allocations = 0;
  counting = true;
  f();
  counting = false;
  return allocations.load();
}

// Makes `p` look used to the optimiser: Clang may otherwise leave out the allocation of a vector
// that nothing reads (C++14 lets a compiler merge or omit new-expressions).
void keep(const void* p) { asm volatile("" : : "g"(p) : "memory"); }

TEST(TrackerAllocation, TheCounterSeesVectorsAndEigenMatrices) {
  EXPECT_GE(allocations_in([] {
              const std::vector<int> probe(10);
              keep(probe.data());
            }),
            1);
#ifdef S2KF_COUNTS_MALLOC
  EXPECT_GE(allocations_in([] {
              Eigen::MatrixXd m(10, 10);
              m.setZero();
            }),
            1);
#endif
}

// Frames of the handstand with hidden blocks that change every frame, through a tracker with
// `options`: no allocation once the first frames have sized the buffers.
void expect_steady_state_frames_to_allocate_nothing(const track::TrackerOptions& options) {
  const c3d::Recording recording = c3d::read_c3d(std::string(S2KF_DATA_DIR) + "/handstand.c3d");
  std::vector<std::string> labels;
  for (const auto& label : recording.info.labels) labels.push_back(label.name);
  body::BodyModel model = body::mmm_body_model(1000);
  const body::MarkerMapping mapping = body::map_markers(labels, model.marker_names());
  calibration::HeightEstimator heights(model, mapping);
  for (Eigen::Index f = 0; f < recording.frame_count(); f += 10)
    heights.add_frame(recording.frame(f), recording.visible.col(f));
  model = model.scaled(heights.height_mm().value_or(1750));
  ASSERT_EQ(mapping.markers_used(), 50);
  track::Tracker tracker(model, mapping, options, recording.info.rate, test::tracker_samples());

  // Frames and visibility prepared up front: hidden blocks of 0..24 markers that move every frame,
  // one frame with every marker hidden and one with a NaN coordinate on a "visible" marker.
  const Eigen::Index points = recording.point_count();
  const int warmup = 20, measured = 50;
  std::vector<Eigen::Matrix3Xd> frames;
  std::vector<Visible> visible;
  for (int f = 0; f < warmup + measured; ++f) {
    frames.emplace_back(recording.frame(f));
    Visible v = recording.visible.col(f);
    if (f >= warmup) {
      const int hidden = (f * 7) % 25;
      for (Eigen::Index p = 0; p < points; ++p)
        if ((p + 3 * f) % points < hidden) v(p) = false;
    }
    visible.push_back(v);
  }
  visible[warmup + 10].setConstant(false);
  frames[warmup + 20](1, 5) = std::numeric_limits<double>::quiet_NaN();

  for (int f = 0; f < warmup; ++f) ASSERT_TRUE(tracker.process(frames[f], visible[f]).tracked);
  std::vector<FilterStatus> statuses(measured);
  std::vector<int> visible_counts(measured);
  const long count = allocations_in([&] {
    for (int f = warmup; f < warmup + measured; ++f) {
      const track::FrameEstimate& e = tracker.process(frames[f], visible[f]);
      statuses[f - warmup] = e.status;
      visible_counts[f - warmup] = e.visible_markers;
    }
  });
  EXPECT_EQ(count, 0);
  for (int k = 0; k < measured; ++k) {
    if (k == 10) {
      EXPECT_EQ(statuses[k], FilterStatus::nothing_observed);
      EXPECT_EQ(visible_counts[k], 0);
    } else {
      EXPECT_EQ(statuses[k], FilterStatus::ok) << "frame " << warmup + k;
      EXPECT_GE(visible_counts[k], 25);
    }
    int expected_visible = 0;  // mapped markers visible with finite coordinates
    for (int m = 0; m < model.marker_count(); ++m) {
      const int p = mapping.point_of_marker[m];
      expected_visible += p >= 0 && visible[warmup + k](p) && frames[warmup + k].col(p).allFinite();
    }
    EXPECT_EQ(visible_counts[k], expected_visible) << "frame " << warmup + k;
    if (k == 20) {
      EXPECT_TRUE(visible[warmup + k](5));  // the NaN point was marked visible, and is not counted
      EXPECT_LT(visible_counts[k], visible[warmup + k].count());
    }
  }

  // What the allocation-free finish() reports is what the single-pose functions give.
  const track::FrameEstimate& e = tracker.estimate();
  const Eigen::Matrix3Xd expected = body::marker_positions(tracker.model(), e.pose);
  ASSERT_EQ(e.predicted_markers.cols(), expected.cols());
  EXPECT_LT((e.predicted_markers - expected).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((e.pose.root_rotation() - e.root_rotation).cwiseAbs().maxCoeff(), 1e-12);
  double mean_distance = 0;
  int distances = 0;
  for (Eigen::Index m = 0; m < e.marker_distance.size(); ++m)
    if (std::isfinite(e.marker_distance(m))) {
      const Eigen::Vector3d measured_point = frames.back().col(mapping.point_of_marker[m]);
      EXPECT_NEAR(e.marker_distance(m), (measured_point - expected.col(m)).norm(), 1e-6);
      mean_distance += e.marker_distance(m);
      ++distances;
    }
  ASSERT_GT(distances, 0);
  EXPECT_NEAR(e.mean_marker_distance, mean_distance / distances, 1e-9);
  EXPECT_LT(e.mean_marker_distance, 60.0);  // still tracking (measured about 20 mm)
}

TEST(TrackerAllocation, SteadyStateFramesWithChangingOcclusionAllocateNothing) {
  expect_steady_state_frames_to_allocate_nothing(track::TrackerOptions{});
}

TEST(TrackerAllocation, NorWithTheRootsProductsInTheInformationForm) {
  track::TrackerOptions options;
  options.information_form_root_products = true;
  expect_steady_state_frames_to_allocate_nothing(options);
}

}  // namespace
