// Defines S2KF_TEST_UNDER_ASAN when the test is compiled with AddressSanitizer (GCC sets
// __SANITIZE_ADDRESS__, Clang answers __has_feature): tests that count allocations or measure
// resident memory skip themselves there, since ASan's own allocator and shadow memory decide both.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define S2KF_TEST_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define S2KF_TEST_UNDER_ASAN 1
#endif
#endif

/// First statement of a test that tracks whole recordings end to end (tens of seconds under the
/// sanitizers). The sanitizer pass skips such tests, and says so: the shorter tests and the few
/// whole-recording tests left unmarked run the same code there, and the release pass runs them all.
#ifdef S2KF_TEST_UNDER_ASAN
#define S2KF_SKIP_UNDER_SANITIZERS() GTEST_SKIP() << "tracks whole recordings; the release pass runs it"
#else
#define S2KF_SKIP_UNDER_SANITIZERS() static_cast<void>(0)
#endif
