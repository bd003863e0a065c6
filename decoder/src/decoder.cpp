// Placeholder until the format issue lands: every stream is refused with a clear message.
#include "pmz/decoder.hpp"

namespace pmz {

const char* status_name(Status s) {
  switch (s) {
    case Status::ok: return "ok";
    case Status::bad_magic: return "bad magic";
    case Status::bad_version: return "unsupported version";
    case Status::bad_checksum: return "bad checksum";
    case Status::corrupt: return "corrupt stream";
    case Status::limit_exceeded: return "limit exceeded";
    case Status::truncated: return "truncated stream";
    case Status::out_of_memory: return "out of memory";
  }
  return "unknown status";
}

struct Decoder::Impl {
  DecoderLimits limits;
  Status status = Status::ok;
  std::string message;
  StreamInfo info;
  MeshChanges changes;
  uint64_t consumed = 0;
};

Decoder::Decoder(const DecoderLimits& limits) : impl_(new Impl) { impl_->limits = limits; }
Decoder::~Decoder() = default;
Decoder::Decoder(Decoder&&) noexcept = default;
Decoder& Decoder::operator=(Decoder&&) noexcept = default;

Status Decoder::feed(const void*, size_t size) {
  if (size == 0) return impl_->status;
  impl_->status = Status::corrupt;
  impl_->message = "pmz decoder not implemented yet";
  return impl_->status;
}
Status Decoder::finish() { return impl_->status == Status::ok ? Status::truncated : impl_->status; }
Status Decoder::status() const { return impl_->status; }
const std::string& Decoder::error_message() const { return impl_->message; }
const StreamInfo& Decoder::info() const { return impl_->info; }
uint64_t Decoder::bytes_consumed() const { return impl_->consumed; }
uint64_t Decoder::refine(uint64_t) { return 0; }
uint64_t Decoder::coarsen(uint64_t) { return 0; }
void Decoder::set_face_target(uint64_t) {}
void Decoder::set_split_target(uint64_t) {}
uint64_t Decoder::splits_applied() const { return 0; }
uint64_t Decoder::splits_available() const { return 0; }
uint32_t Decoder::vertex_count() const { return 0; }
uint32_t Decoder::face_count() const { return 0; }
const float* Decoder::positions() const { return nullptr; }
const uint32_t* Decoder::indices() const { return nullptr; }
const uint32_t* Decoder::split_parents() const { return nullptr; }
const MeshChanges& Decoder::changes() const { return impl_->changes; }
void Decoder::clear_changes() { impl_->changes = {}; }

}  // namespace pmz
