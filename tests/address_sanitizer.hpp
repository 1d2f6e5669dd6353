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
