#pragma once
/// A checkpoint: the complete state of a run (its engine and the run loop), serialised
/// verbatim as binary so that a run restored from it continues with the same bits as if
/// it had never stopped (docs/checkpoints.md).
///
/// The blob: a header (magic "PDAMPCKP", format version, pdamp version, store schema),
/// the payload — named sections of raw values, each part checks its own name on the way
/// back — and an FNV-1a checksum of everything before it. Values are written as their
/// bytes on this machine: a checkpoint is read back by the same build of pdamp (which
/// resume checks), not exchanged between machines of other byte orders.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "pdamp/errors.hpp"

namespace pdamp {

/// Both directions have `section` and `io`, so that each part of an engine lists what it
/// saves once, in one function template over the writer (with the part const) and the
/// reader: `template <class Self, class Archive> static void transfer(Self&, Archive&)`.

/// The format of the blob; a reader refuses any other. Raised whenever an engine saves
/// more or other state (2: the hard engine's rider search boxes).
inline constexpr std::uint32_t checkpoint_format_version = 2;

class CheckpointWriter {
 public:
  /// `schema_version`: the store's schema the run is kept in (the header records it).
  explicit CheckpointWriter(int schema_version);

  /// Starts a part's section: a reader expects the same name there.
  void section(std::string_view name);

  template <class T>
  requires std::is_trivially_copyable_v<T>
  void put(const T& value) { append(&value, sizeof value); }
  template <class T, class Allocator>
  requires std::is_trivially_copyable_v<T>
  void put(const std::vector<T, Allocator>& values) {
    put(static_cast<std::uint64_t>(values.size()));
    append(values.data(), values.size() * sizeof(T));
  }
  template <class T>
  requires std::is_trivially_copyable_v<T>
  void put(std::span<const T> values) {
    put(static_cast<std::uint64_t>(values.size()));
    append(values.data(), values.size_bytes());
  }
  void put(const std::vector<bool>& values);
  void put(std::string_view text);
  template <class Scalar, int Rows, int Cols>
  void put(const Eigen::Matrix<Scalar, Rows, Cols>& m) {
    put(static_cast<std::int64_t>(m.rows()));
    put(static_cast<std::int64_t>(m.cols()));
    append(m.data(), static_cast<std::size_t>(m.size()) * sizeof(Scalar));
  }

  template <class T>
  void io(const T& value) {
    put(value);
  }
  /// Memory the engine sizes itself (checked on the way back).
  template <class T>
  void io(std::span<const T> values, std::string_view) {
    put(values);
  }

  /// A part with its own save().
  template <class Part>
  void part(const Part& p) {
    p.save(*this);
  }

  /// The blob, with its checksum; the writer is spent.
  std::vector<std::byte> finish();

 private:
  void append(const void* data, std::size_t bytes);
  std::vector<std::byte> bytes_;
};

class CheckpointReader {
 public:
  /// Checks the header and the checksum; throws InputError naming what is wrong (not a
  /// checkpoint, another format, damaged).
  explicit CheckpointReader(std::span<const std::byte> blob);

  const std::string& pdamp_version() const { return pdamp_version_; }
  int schema_version() const { return schema_version_; }

  /// Throws RuntimeFailure unless the next section is `name`.
  void section(std::string_view name);

  template <class T>
  requires std::is_trivially_copyable_v<T>
  void get(T& value) { take(&value, sizeof value); }
  template <class T>
  requires std::is_trivially_copyable_v<T> T get() {
    T value;
    take(&value, sizeof value);
    return value;
  }
  template <class T, class Allocator>
  requires std::is_trivially_copyable_v<T>
  void get(std::vector<T, Allocator>& values) {
    values.resize(count(sizeof(T)));
    take(values.data(), values.size() * sizeof(T));
  }
  /// Into memory of the size the engine already has: throws RuntimeFailure naming `what`
  /// if the checkpoint holds another count.
  template <class T>
  requires std::is_trivially_copyable_v<T>
  void get(std::span<T> values, std::string_view what) {
    if (count(sizeof(T)) != values.size()) throw damaged(std::string(what) + " of another size");
    take(values.data(), values.size_bytes());
  }
  void get(std::vector<bool>& values);
  void get(std::string& text);
  template <class Scalar, int Rows, int Cols>
  void get(Eigen::Matrix<Scalar, Rows, Cols>& m) {
    const auto rows = get<std::int64_t>(), cols = get<std::int64_t>();
    if ((Rows != Eigen::Dynamic && rows != Rows) || (Cols != Eigen::Dynamic && cols != Cols) || rows < 0 || cols < 0 ||
        (rows > 0 &&
         static_cast<std::uint64_t>(cols) > remaining() / sizeof(Scalar) / static_cast<std::uint64_t>(rows))) {
      throw damaged("a matrix of " + std::to_string(rows) + " x " + std::to_string(cols));
    }
    m.resize(rows, cols);
    take(m.data(), static_cast<std::size_t>(m.size()) * sizeof(Scalar));
  }
  template <class T>
  void io(T& value) {
    get(value);
  }
  template <class T>
  void io(std::span<T> values, std::string_view what) {
    get(values, what);
  }
  /// A part with its own restore().
  template <class Part>
  void part(Part& p) {
    p.restore(*this);
  }
  /// Reads `expected` and throws RuntimeFailure naming `what` if the checkpoint holds another value.
  template <class T>
  void expect(const T& expected, std::string_view what) {
    if (get<T>() != expected) throw damaged(std::string(what) + " differs from this engine's");
  }
  /// Throws RuntimeFailure unless everything was read.
  void finish() const;

 private:
  void take(void* data, std::size_t bytes);
  /// A count of elements of `element_bytes` each, checked against what is left.
  std::size_t count(std::size_t element_bytes);
  std::size_t remaining() const { return end_ - at_; }
  RuntimeFailure damaged(const std::string& what) const;

  std::span<const std::byte> blob_;
  std::size_t at_ = 0, end_ = 0;
  std::string pdamp_version_;
  int schema_version_ = 0;
};

}  // namespace pdamp
