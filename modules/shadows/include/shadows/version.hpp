#pragma once
// The shadow module's version (the installed CMake package's version is read from here) and the macro
// marking its API: a shared libshadows is built with hidden visibility and exports only what it marks.
#define SHADOWS_VERSION_MAJOR 1
#define SHADOWS_VERSION_MINOR 0
#define SHADOWS_VERSION_PATCH 0

#if defined(__GNUC__) || defined(__clang__)
#define SHADOWS_API __attribute__((visibility("default")))
#else
#define SHADOWS_API
#endif
