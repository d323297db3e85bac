#pragma once
/// The open contacts of one chunk of spheres — the pairs its spheres own and their wall
/// contacts — kept compactly: only touching contacts have an entry (a settled bed lists
/// ~9 pairs per sphere within the skin, of which ~3 touch; a shaken one ~1 of ~5).

#include <vector>

#include "pdamp/model/checkpoint.hpp"
#include "soft/contact_law.hpp"
#include "soft/sphere_arrays.hpp"

namespace pdamp::soft {

class ContactTable {
 public:
  /// The entry of a contact that is not open: a blank history, never written, so that a
  /// contact is read the same way whether it is open or not.
  static constexpr int none = 0;

  ContactTable() : entries_(1) {}

  const ContactHistory<>& operator[](int contact) const { return entries_[contact]; }
  ContactHistory<>& operator[](int contact) { return entries_[contact]; }
  /// The entries as one array of doubles, for SIMD gathers.
  const double* data() const { return &entries_.front().tangential_displacement_m.x; }

  /// A new entry (to be written), reusing a closed contact's.
  int open() {
    if (!free_.empty()) {
      const int contact = free_.back();
      free_.pop_back();
      return contact;
    }
    return append({});
  }

  void close(int contact) { free_.push_back(contact); }

  /// Empties the table, with room for `entries` and some more.
  void clear(int entries) {
    entries_.resize(1);
    entries_.reserve(entries + entries / 16 + 4);
    free_.clear();
  }
  /// Empties the table and frees its memory.
  void release() {
    entries_ = std::vector<ContactHistory<>>(1);
    free_ = std::vector<int>();
  }
  /// Its entries and free list verbatim (soft_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

  /// Appends an entry; returns its index.
  int append(const ContactHistory<>& history) {
    push_back_compactly(entries_, history);
    return static_cast<int>(entries_.size()) - 1;
  }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);

  std::vector<ContactHistory<>> entries_;
  std::vector<int> free_;
};

static_assert(sizeof(ContactHistory<>) == 7 * sizeof(double), "entries are gathered as arrays of seven doubles");

}  // namespace pdamp::soft
