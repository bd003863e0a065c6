// SPDX-License-Identifier: MIT
// The outcome of decoding .pmz bytes: what the codec's own stream decoders (format/, e.g.
// decode_base) return when a caller must tell failures apart, and the decoder's public status
// (installed with pmz/decoder.hpp, which includes it; status_name is defined in the decoder
// library, whose messages use it). The error convention of the libraries is in
// docs/design.md section 8 ("Errors").
#pragma once

#include "pmz/export.h"

namespace pmz {

enum class Status : int {
  ok = 0,
  bad_magic = 1,       // not a .pmz stream
  bad_version = 2,     // a major version this decoder does not read
  bad_checksum = 3,    // a chunk's checksum does not match its bytes
  corrupt = 4,         // bytes that parse but describe an impossible mesh or stream
  limit_exceeded = 5,  // counts beyond DecoderLimits or beyond what the input can hold
  truncated = 6,       // only from finish(): the stream ended before its end marker
  out_of_memory = 7,
};

// "corrupt stream", "truncated stream", ... (the decoder's messages start with it).
PMZ_API const char* status_name(Status s);

}  // namespace pmz
