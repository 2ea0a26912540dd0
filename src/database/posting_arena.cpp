// The posting arena: the blocks the tail's posting lists live in.
#include "binbow/database.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

#include "binbow/error.h"
#include "database/database_impl.h"

namespace binbow {

namespace detail {

void populate(void* data, std::size_t bytes) noexcept {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
  constexpr std::size_t kWorthACall = std::size_t{2} << 20;
  if (bytes < kWorthACall) return;
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto begin = (reinterpret_cast<std::uintptr_t>(data) + page - 1) & ~(page - 1);
  const auto end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(page - 1);
  // Older kernels refuse the advice: the pages then fault in as they are written.
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE);
#else
  (void)data;
  (void)bytes;
#endif
}

void* allocate_huge(std::size_t bytes) {
  constexpr std::size_t kHugePage = std::size_t{2} << 20;
  void* data = std::aligned_alloc(kHugePage, bytes);
  if (data == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  madvise(data, bytes, MADV_HUGEPAGE);  // only advice: 4 KiB pages otherwise
#endif
  return data;
}

std::uint32_t PostingArena::new_chunk(std::size_t postings) {
  // Addresses are 32 bits: chunk index, then kChunkBits of position.
  if (chunks_.size() >= (std::size_t{1} << (32 - kChunkBits)))
    throw InvalidArgument("Database: the tail outgrew its 32 GiB of addresses");
  chunk_starts_.reserve(chunks_.size() + 1);
  chunk_postings_.reserve(chunks_.size() + 1);
  // Left uninitialised; a block larger than a chunk gets a chunk of its own,
  // whose size is rounded up to huge pages.
  const std::size_t huge_postings = (std::size_t{2} << 20) / sizeof(TailPosting);
  postings = (postings + huge_postings - 1) / huge_postings * huge_postings;
  chunks_.emplace_back(static_cast<TailPosting*>(allocate_huge(postings * sizeof(TailPosting))));
  chunk_starts_.push_back(chunks_.back().get());
  chunk_postings_.push_back(postings);
  chunk_bytes_ += postings * sizeof(TailPosting);
  return static_cast<std::uint32_t>((chunks_.size() - 1) << kChunkBits);
}

std::uint32_t PostingArena::allocate(std::uint32_t capacity) {
  const auto size_class = static_cast<unsigned>(__builtin_ctz(capacity));
  const std::uint32_t reused = free_lists_[size_class];
  if (reused != kNoBlock) {
    std::memcpy(&free_lists_[size_class], at(reused), sizeof(std::uint32_t));
    // The next allocation of this size reads that block: fetch it now.
    if (free_lists_[size_class] != kNoBlock) __builtin_prefetch(at(free_lists_[size_class]));
    return reused;
  }
  constexpr std::uint32_t kChunkPostings = std::uint32_t{1} << kChunkBits;
  if (capacity > kChunkPostings) return new_chunk(capacity);  // a chunk of its own
  if (bump_left_ < capacity) {
    bump_ = spare_begin_ < spare_end_ ? static_cast<std::uint32_t>(spare_begin_++ << kChunkBits)
                                      : new_chunk(kChunkPostings);
    bump_left_ = kChunkPostings;
  }
  const std::uint32_t block = bump_;
  bump_ += capacity;
  bump_left_ -= capacity;
  return block;
}

void PostingArena::release(std::uint32_t block, std::uint32_t capacity) noexcept {
  const auto size_class = static_cast<unsigned>(__builtin_ctz(capacity));
  std::memcpy(at(block), &free_lists_[size_class], sizeof(std::uint32_t));
  free_lists_[size_class] = block;
}

void PostingArena::reset() noexcept {
  // Blocks larger than a chunk have chunks of their own: those go.
  constexpr std::size_t kChunkPostings = std::size_t{1} << kChunkBits;
  std::size_t kept = 0;
  for (std::size_t c = 0; c < chunks_.size(); ++c) {
    if (chunk_postings_[c] != kChunkPostings) continue;
    chunks_[kept] = std::move(chunks_[c]);
    chunk_starts_[kept] = chunk_starts_[c];
    chunk_postings_[kept] = kChunkPostings;
    ++kept;
  }
  chunks_.resize(kept);
  chunk_starts_.resize(kept);
  chunk_postings_.resize(kept);
  chunk_bytes_ = kept * kChunkPostings * sizeof(TailPosting);
  std::fill(std::begin(free_lists_), std::end(free_lists_), kNoBlock);
  bump_ = 0;
  bump_left_ = 0;
  spare_begin_ = 0;
  spare_end_ = kept;
}

void PostingArena::clear() noexcept {
  chunks_.clear();
  chunk_starts_.clear();
  chunk_postings_.clear();
  std::fill(std::begin(free_lists_), std::end(free_lists_), kNoBlock);
  bump_ = 0;
  bump_left_ = 0;
  spare_begin_ = 0;
  spare_end_ = 0;
  chunk_bytes_ = 0;
}

}  // namespace detail

}  // namespace binbow
