// SPDX-License-Identifier: MIT
// Build hints for the WebAssembly decoder (scripts/web.sh); natively they expand to what the
// code would say without them, so native code is the same with or without this header.
#pragma once

#include <cstdint>
#include <new>  // std::bad_alloc in PMZ_CATCH_BAD_ALLOC
#include <string>
#include <type_traits>

// The WebAssembly build has a size budget (scripts/web.sh): there, once-per-file set-up (model
// initialization, chunk and base mesh decoding, buffer growth) is optimized for size with all it
// inlines (its LTO inlines every single-caller function). No effect elsewhere.
#if defined(__wasm__)
#define PMZ_SMALL_IN_WASM [[clang::minsize]]
#else
#define PMZ_SMALL_IN_WASM
#endif

// Once-per-file code built for size everywhere (the native decoder library's size budget).
// GCC spells it optimize("Os"); clang (the fuzz and WebAssembly builds) ignores that attribute
// with a warning, and says minsize.
#if defined(__clang__)
#define PMZ_SMALL [[clang::minsize]]
#else
#define PMZ_SMALL [[gnu::optimize("Os")]]
#endif

// A cache-line prefetch of an address inside a live buffer. WebAssembly has no prefetch
// instruction (clang drops __builtin_prefetch there), so the wasm build loads the byte instead:
// the out-of-order core issues the miss early just the same, only its retirement waits for it
// (bunny00-loop2 in node: docs/design.md section 9). Only for an address inside a
// buffer (a wasm load beyond memory traps). A macro: native code stays the same as
// __builtin_prefetch written out (GCC inlines differently around a wrapper function).
#if defined(__wasm__)
#define PMZ_PREFETCH(p) ((void)*reinterpret_cast<const volatile uint8_t*>(p))
#else
#define PMZ_PREFETCH(p) __builtin_prefetch(p)
#endif

// Out of memory: a std::bad_alloc caught where the decoder reports Status::out_of_memory. The
// WebAssembly build compiles without exceptions (scripts/web.sh: -fno-exceptions drops the
// throw/catch runtime and its RTTI, ~1.3 KB), where a failed allocation aborts the instance and
// web/src/index.js reports out_of_memory from then on. There the try block runs as a plain block
// and the handler is never reached. Natively (exceptions on) these are try / catch written out.
#if defined(__cpp_exceptions)
#define PMZ_TRY try
#define PMZ_CATCH_BAD_ALLOC catch (const std::bad_alloc&)
#else
#define PMZ_TRY if (true)
#define PMZ_CATCH_BAD_ALLOC else
#endif

// The decimal text of an unsigned number in an error message. Natively std::to_string; the
// WebAssembly build spells it with a short loop (coding.cpp): libc++'s to_string overloads and
// their digit and power-of-ten tables are ~0.9 KB there.
#if defined(__wasm__)
namespace pmz {
std::string decimal_in_wasm(uint64_t v);
template <class T>
std::string decimal_of_unsigned(T v) {
  static_assert(std::is_unsigned_v<T>, "error message numbers are unsigned");
  return decimal_in_wasm(v);
}
}  // namespace pmz
#define PMZ_DECIMAL(x) ::pmz::decimal_of_unsigned(x)
#else
#define PMZ_DECIMAL(x) std::to_string(x)
#endif
