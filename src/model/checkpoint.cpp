#include "pdamp/model/checkpoint.hpp"

#include <array>

#include "pdamp/version.hpp"

namespace pdamp {
namespace {

constexpr std::array<char, 8> magic{'P', 'D', 'A', 'M', 'P', 'C', 'K', 'P'};

/// FNV-1a, 64 bits, eight bytes at a time folded byte by byte: cheap next to the copies.
std::uint64_t checksum(std::span<const std::byte> bytes) {
  std::uint64_t hash = 14695981039346656037ull;
  for (const std::byte b : bytes) hash = (hash ^ static_cast<std::uint64_t>(b)) * 1099511628211ull;
  return hash;
}

}  // namespace

CheckpointWriter::CheckpointWriter(int schema_version) {
  append(magic.data(), magic.size());
  put(checkpoint_format_version);
  put(std::string_view(version_string));
  put(static_cast<std::int32_t>(schema_version));
}

void CheckpointWriter::section(std::string_view name) { put(name); }

void CheckpointWriter::put(const std::vector<bool>& values) {
  put(static_cast<std::uint64_t>(values.size()));
  for (const bool v : values) put(static_cast<std::uint8_t>(v));
}

void CheckpointWriter::put(std::string_view text) {
  put(static_cast<std::uint64_t>(text.size()));
  append(text.data(), text.size());
}

void CheckpointWriter::append(const void* data, std::size_t bytes) {
  const auto* first = static_cast<const std::byte*>(data);
  bytes_.insert(bytes_.end(), first, first + bytes);
}

std::vector<std::byte> CheckpointWriter::finish() {
  put(checksum(bytes_));
  return std::move(bytes_);
}

CheckpointReader::CheckpointReader(std::span<const std::byte> blob) : blob_(blob) {
  constexpr std::size_t sum_bytes = sizeof(std::uint64_t);
  if (blob.size() < magic.size() + sum_bytes || std::memcmp(blob.data(), magic.data(), magic.size()) != 0) {
    throw InputError("the checkpoint is not one pdamp wrote (" + std::to_string(blob.size()) +
                     " bytes without its mark)");
  }
  end_ = blob.size() - sum_bytes;
  std::uint64_t stored = 0;
  std::memcpy(&stored, blob.data() + end_, sum_bytes);
  if (stored != checksum(blob.first(end_))) {
    throw InputError("the checkpoint is damaged: its checksum does not match its " + std::to_string(blob.size()) +
                     " bytes");
  }
  at_ = magic.size();
  if (const auto format = get<std::uint32_t>(); format != checkpoint_format_version) {
    throw InputError("the checkpoint has format " + std::to_string(format) + "; this pdamp reads format " +
                     std::to_string(checkpoint_format_version));
  }
  get(pdamp_version_);
  schema_version_ = get<std::int32_t>();
}

void CheckpointReader::section(std::string_view name) {
  std::string found;
  get(found);
  if (found != name) throw damaged("section '" + found + "' where '" + std::string(name) + "' belongs");
}

void CheckpointReader::get(std::vector<bool>& values) {
  values.resize(count(1));
  for (std::size_t k = 0; k < values.size(); ++k) values[k] = get<std::uint8_t>() != 0;
}

void CheckpointReader::get(std::string& text) {
  text.resize(count(1));
  take(text.data(), text.size());
}

void CheckpointReader::finish() const {
  if (at_ != end_) throw damaged(std::to_string(end_ - at_) + " bytes left over");
}

void CheckpointReader::take(void* data, std::size_t bytes) {
  if (bytes > remaining()) throw damaged("it ends early");
  if (bytes > 0) std::memcpy(data, blob_.data() + at_, bytes);
  at_ += bytes;
}

std::size_t CheckpointReader::count(std::size_t element_bytes) {
  const auto n = get<std::uint64_t>();
  if (element_bytes > 0 && n > remaining() / element_bytes) throw damaged("a count of " + std::to_string(n));
  return static_cast<std::size_t>(n);
}

RuntimeFailure CheckpointReader::damaged(const std::string& what) const {
  return RuntimeFailure("the checkpoint does not fit this engine at byte " + std::to_string(at_) + ": " + what);
}

}  // namespace pdamp
