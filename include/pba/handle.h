// pba handles: generation-checked ids for entities and components (Box2D v3's b2BodyId
// idea in C++). A handle is an index into a slot table plus the slot's generation; the
// generation changes every time the slot is freed, so a handle kept after destroy() is
// recognised as stale and rejected with an Error instead of touching a reused slot.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "pba/core.h"

namespace pba {

/// A generation-checked id. `Tag` makes entity ids and particle ids distinct types.
/// A default-constructed handle is null (never valid).
template <class Tag>
struct Handle {
  /// Slot index in the owner's table; kNullIndex for the null handle.
  std::uint32_t index = kNullIndex;
  /// Generation of the slot when the handle was issued (starts at 1; 0 is never issued).
  std::uint32_t generation = 0;

  /// Index value of the null handle.
  static constexpr std::uint32_t kNullIndex = std::numeric_limits<std::uint32_t>::max();
  /// True unless this is the null handle (says nothing about staleness: ask the owner).
  bool is_null() const { return index == kNullIndex; }
  bool operator==(const Handle&) const = default;
};

/// The slot table behind a family of handles: allocates indices (reusing freed ones in
/// LIFO order, deterministically), bumps a slot's generation when it is freed, and checks
/// handles. Growth allocates; create()/destroy() with a reused slot never do.
///
/// A slot issues generations 1, 2, ..., kLastGeneration and is then retired for good: its
/// last handle destroyed, it is never reused, so a generation never wraps around to one a
/// kept handle still holds (Box2D v3's 16-bit and Jolt's 8-bit generations wrap, and a
/// handle kept over 65536 or 256 reuses of its slot names the new object). With 32 bits a
/// slot retires after 4.3e9 destroys, keeping 5 bytes of the table; `kLastGeneration` is a
/// parameter so that tests can reach it.
///
/// The table holds at most `kMaxSlots` slots, indices 0 .. kMaxSlots - 1: by default
/// 0xFFFFFFFF, so the last index issued is 0xFFFFFFFE and the null handle's kNullIndex is
/// never handed out. Past it create() throws Error (a parameter, as kLastGeneration, so that
/// tests can reach it).
template <class Tag, std::uint32_t kLastGeneration = std::numeric_limits<std::uint32_t>::max(),
          std::uint32_t kMaxSlots = Handle<Tag>::kNullIndex>
class HandlePool {
  static_assert(kLastGeneration >= 1, "a slot issues at least generation 1");
  static_assert(kMaxSlots >= 1 && kMaxSlots <= Handle<Tag>::kNullIndex,
                "the null handle's index is never a slot's");

 public:
  using Id = Handle<Tag>;

  /// Issues a handle, reusing the most recently freed slot if any. Throws Error when every
  /// one of the kMaxSlots slots is live or retired (the next index would be kMaxSlots; at
  /// the default, the null handle's 0xFFFFFFFF, which handed out as a live handle read as null).
  Id create() {
    // reuse a freed slot (its generation was bumped at destroy)
    if (!free_.empty()) {
      const std::uint32_t i = free_.back();
      free_.pop_back();
      alive_[i] = kAlive;
      ++live_;
      return Id{i, generation_[i]};
    }
    // or append a new slot at generation 1, while there is an index for it
    if (generation_.size() >= kMaxSlots)
      throw Error("HandlePool::create: every one of the " + std::to_string(kMaxSlots) +
                  " slots is live or retired (" + std::to_string(live_) + " live): index " +
                  std::to_string(generation_.size()) + " is past the last, " + std::to_string(kMaxSlots - 1) +
                  (kMaxSlots == Handle<Tag>::kNullIndex ? " (0xFFFFFFFF is the null handle's)" : ""));
    generation_.push_back(1);
    alive_.push_back(kAlive);
    ++live_;
    return Id{static_cast<std::uint32_t>(generation_.size() - 1), 1};
  }
  /// Frees the handle's slot (throws Error naming `where` if the handle is stale or null).
  void destroy(Id id, std::string_view where) {
    require(id, where);
    --live_;
    // a slot that issued its last generation retires: never reused, so never wrapped around
    if (generation_[id.index] == kLastGeneration) {
      alive_[id.index] = kRetired;
      return;
    }
    // bump the generation so every copy of `id` becomes stale
    alive_[id.index] = kFree;
    ++generation_[id.index];
    free_.push_back(id.index);
  }
  /// True when `id` names a live slot with a matching generation.
  bool valid(Id id) const {
    return id.index < generation_.size() && alive_[id.index] == kAlive && generation_[id.index] == id.generation;
  }
  /// Throws Error naming `where` unless valid(id). A handle carries no mark of the pool that
  /// issued it, so a handle of another pool (another World's or system's) is told apart only
  /// when this pool never issued its index or generation: "<where>: invalid handle (index 7
  /// was never issued here: a handle of another World or system)", or "(index 0 at generation
  /// 3 was never issued here, the slot is at generation 1[ and free]: ...)" for a generation
  /// 0, one beyond the slot's, or a free slot's own (bumped at destroy, not issued until the
  /// slot is reused); otherwise the message names both possibilities, "<where>: stale handle
  /// (index i, generation g; the slot is now at generation h[ and free]): destroyed since,
  /// or a handle of another World or system" (a retired slot: "; the slot is retired, its
  /// generations used up"); or "<where>: null handle".
  void require(Id id, std::string_view where) const {
    if (valid(id)) return;
    if (id.is_null()) throw Error(std::string(where) + ": null handle");
    static constexpr const char* kOther = ": a handle of another World or system)";
    if (id.index >= generation_.size())
      throw Error(std::string(where) + ": invalid handle (index " + std::to_string(id.index) +
                  " was never issued here" + kOther);
    // generations only grow (a slot retires instead of wrapping around); a free slot's own was
    // never issued (destroy bumped it past the last one issued); a retired slot issued all
    const std::uint32_t cur = generation_[id.index];
    const std::uint8_t state = alive_[id.index];
    const char* and_free = state == kFree ? " and free" : "";
    if (id.generation == 0 || id.generation > cur || (id.generation == cur && state == kFree))
      throw Error(std::string(where) + ": invalid handle (index " + std::to_string(id.index) + " at generation " +
                  std::to_string(id.generation) + " was never issued here, the slot is at generation " +
                  std::to_string(cur) + and_free + kOther);
    throw Error(std::string(where) + ": stale handle (index " + std::to_string(id.index) + ", generation " +
                std::to_string(id.generation) +
                (state == kRetired ? std::string("; the slot is retired, its generations used up")
                                   : "; the slot is now at generation " + std::to_string(cur) + and_free) +
                "): destroyed since, or a handle of another World or system");
  }
  /// The current generation of slot `index` (for tests and debugging).
  std::uint32_t generation(std::uint32_t index) const { return generation_.at(index); }
  /// The same without the range check, for loops over slots known to exist (index < slots()).
  std::uint32_t generation_unchecked(std::uint32_t index) const { return generation_[index]; }
  /// Live handles.
  std::size_t size() const { return live_; }
  /// Slots ever issued (live, free and retired): the table's capacity in use.
  std::size_t slots() const { return generation_.size(); }
  /// Reserves room for `n` slots so creating up to n handles never allocates.
  void reserve(std::size_t n) {
    generation_.reserve(n);
    alive_.reserve(n);
    free_.reserve(n);
  }

 private:
  std::vector<std::uint32_t> generation_;
  // a slot's state: alive, free (on free_, at the generation its next handle gets) or retired
  static constexpr std::uint8_t kFree = 0, kAlive = 1, kRetired = 2;
  std::vector<std::uint8_t> alive_;
  std::vector<std::uint32_t> free_;
  std::size_t live_ = 0;
};

}  // namespace pba
