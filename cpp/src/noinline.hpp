// OSTEON_NOINLINE: keep a function out of line, for GCC, Clang and MSVC (the wheel is built with
// all three: pyproject.toml's cibuildwheel Linux, macOS and Windows targets).
#pragma once

#if defined(_MSC_VER)
#define OSTEON_NOINLINE __declspec(noinline)
#else
#define OSTEON_NOINLINE __attribute__((noinline))
#endif
