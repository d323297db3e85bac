#pragma once
/// The open contacts of one chunk of spheres — the pairs its spheres own and their wall
/// contacts — kept compactly: only touching contacts have an entry (a settled bed lists
/// ~9 pairs per sphere within the skin, of which ~3 touch; a shaken one ~1 of ~5).

#include <vector>

#include "pdamp/soft/contact_law.hpp"

namespace pdamp::soft {

class ContactTable {
 public:
  /// The entry of a contact that is not open: a blank history, never written, so that a
  /// contact is read the same way whether it is open or not.
  static constexpr int none = 0;

  struct Entry {
    ContactHistory<> history;
    /// The force and torque a pair contact put on its partner at the last force computation.
    Vec3<double> reaction_force_N, reaction_torque_N_m;
    int partner = -1;  ///< −1 for a wall contact or a free entry
  };

  ContactTable() : entries_(1) {}

  const Entry& operator[](int contact) const { return entries_[contact]; }
  Entry& operator[](int contact) { return entries_[contact]; }
  /// All entries, open or free (a free entry has partner −1).
  const std::vector<Entry>& entries() const { return entries_; }

  /// A new entry, reusing a closed contact's.
  int open(int partner) {
    int contact = static_cast<int>(entries_.size());
    if (free_.empty()) {
      // Grown by a quarter, not doubled: the tables are most of the engine's memory.
      if (entries_.size() == entries_.capacity()) entries_.reserve(entries_.size() + entries_.size() / 4 + 16);
      entries_.emplace_back();
    } else {
      contact = free_.back();
      free_.pop_back();
    }
    entries_[contact].partner = partner;
    return contact;
  }

  void close(int contact) {
    entries_[contact].partner = -1;
    free_.push_back(contact);
  }

  /// Empties the table (keeping its memory).
  void clear() {
    entries_.resize(1);
    free_.clear();
  }
  /// Appends a copy of another table's entry; returns its index here.
  int append(const Entry& entry) {
    entries_.push_back(entry);
    return static_cast<int>(entries_.size()) - 1;
  }
  /// Takes over another table's entries, keeping its own memory where it suffices.
  void copy_from(const ContactTable& other) {
    entries_.assign(other.entries_.begin(), other.entries_.end());
    free_.assign(other.free_.begin(), other.free_.end());
  }

 private:
  std::vector<Entry> entries_;
  std::vector<int> free_;
};

}  // namespace pdamp::soft
