/* Symbol visibility for the shared decoder library. */
#ifndef PMZ_EXPORT_H
#define PMZ_EXPORT_H
#if defined(PMZ_BUILDING_SHARED)
#define PMZ_API __attribute__((visibility("default")))
#else
#define PMZ_API
#endif
#endif
