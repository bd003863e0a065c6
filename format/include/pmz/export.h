// SPDX-License-Identifier: MIT
/* PMZ_API marks the declarations the shared decoder library exports (the C++ decoder API and
   the C API): built with -fvisibility=hidden, everything else stays inside it. PMZ_LOCAL keeps
   a part of an exported class (its Impl) inside. */
#ifndef PMZ_EXPORT_H
#define PMZ_EXPORT_H
#if defined(PMZ_BUILDING_SHARED)
#define PMZ_API __attribute__((visibility("default")))
#define PMZ_LOCAL __attribute__((visibility("hidden")))
#else
#define PMZ_API
#define PMZ_LOCAL
#endif
#endif
