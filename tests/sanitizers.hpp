// SOFTEVO_TEST_ASAN is 1 in a build instrumented by AddressSanitizer, with either compiler:
// GCC defines __SANITIZE_ADDRESS__, clang answers __has_feature(address_sanitizer). Tests whose
// behaviour the sanitizer changes (its allocator ends the process where malloc would return
// null; its shadow memory needs an unlimited address space) ask this.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define SOFTEVO_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SOFTEVO_TEST_ASAN 1
#endif
#endif
#ifndef SOFTEVO_TEST_ASAN
#define SOFTEVO_TEST_ASAN 0
#endif
