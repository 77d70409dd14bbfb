// Seeded mutation fuzzing of every generated decoder (lcm-gen 1.3.1, hardened by
// cmake/HardenLcmDecoders.cmake) through glue::Decode: truncation at every length, trailing
// bytes, wrong fingerprints, absurd counts and NaN/Inf patterns at every offset, and random
// mutations. Each payload either decodes to a message that encodes back to exactly the same
// bytes, or is rejected with a reason; nothing crashes, and the memory a decode allocates is
// bounded by a small multiple of the payload (measured by replacing operator new).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <random>
#include <set>
#include <string>

#include "fuzz_samples.hpp"

// ---- allocation probe: every operator new of this binary, with its size stored before the block.
namespace {

constexpr size_t kHeader = alignof(std::max_align_t);
thread_local bool probe_armed = false;
thread_local size_t probe_live = 0, probe_peak = 0;

void* ProbeAlloc(size_t size) {
  void* raw = std::malloc(size + kHeader);
  if (!raw) throw std::bad_alloc();
  *static_cast<size_t*>(raw) = size;
  if (probe_armed) {
    probe_live += size;
    if (probe_live > probe_peak) probe_peak = probe_live;
  }
  return static_cast<char*>(raw) + kHeader;
}

void ProbeFree(void* p) noexcept {
  if (!p) return;
  void* raw = static_cast<char*>(p) - kHeader;
  const size_t size = *static_cast<size_t*>(raw);
  if (probe_armed) probe_live -= std::min(size, probe_live);
  std::free(raw);
}

}  // namespace

void* operator new(size_t size) { return ProbeAlloc(size); }
void* operator new[](size_t size) { return ProbeAlloc(size); }
void* operator new(size_t size, const std::nothrow_t&) noexcept {
  try {
    return ProbeAlloc(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](size_t size, const std::nothrow_t&) noexcept {
  try {
    return ProbeAlloc(size);
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* p) noexcept { ProbeFree(p); }
void operator delete[](void* p) noexcept { ProbeFree(p); }
void operator delete(void* p, size_t) noexcept { ProbeFree(p); }
void operator delete[](void* p, size_t) noexcept { ProbeFree(p); }

namespace snapnav::fuzz {
namespace {

struct Outcome {
  bool decoded = false;
  std::string reencoded, error;
  size_t peak_bytes = 0;
};

Outcome DecodeProbed(const TypeCase& t, const std::string& bytes) {
  Outcome o;
  probe_live = probe_peak = 0;
  probe_armed = true;
  std::optional<std::string> r;
  try {
    r = t.decode(bytes, &o.error);
  } catch (...) {
    probe_armed = false;
    throw;
  }
  probe_armed = false;
  o.peak_bytes = probe_peak;
  o.decoded = r.has_value();
  if (r) o.reencoded = std::move(*r);
  return o;
}

// What every payload must satisfy.
void Check(const TypeCase& t, const std::string& bytes, const std::string& what) {
  Outcome o;
  ASSERT_NO_THROW(o = DecodeProbed(t, bytes)) << t.name << ": " << what;
  // The decoded message and its encoding: a small multiple of the payload (each array element
  // takes at least one payload byte and at most 24 bytes in memory).
  const size_t bound = 64 * bytes.size() + 4096;
  EXPECT_LE(o.peak_bytes, bound) << t.name << ": " << what << ": " << o.peak_bytes << " bytes allocated for "
                                 << bytes.size();
  if (o.decoded) {
    EXPECT_TRUE(o.reencoded == bytes) << t.name << ": " << what << ": decoded, but encodes to other bytes";
  } else {
    EXPECT_FALSE(o.error.empty()) << t.name << ": " << what << ": rejected without a reason";
  }
}

void Put(std::string* bytes, size_t at, uint64_t value, int n) {
  for (int k = 0; k < n && at + k < bytes->size(); ++k) (*bytes)[at + k] = static_cast<char>((value >> (8 * (n - 1 - k))) & 0xff);
}

uint64_t FloatBits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
uint64_t DoubleBits(double d) {
  uint64_t u;
  std::memcpy(&u, &d, 8);
  return u;
}

TEST(FuzzDecoders, EveryTypeIsCovered) {
  const auto types = AllTypes();
  // One per lcmtypes/snapnav_*.lcm: a new type fails here until it has a sample.
  std::set<std::string> files, names;
  for (const auto& e : std::filesystem::directory_iterator(SNAPNAV_LCMTYPES_DIR)) {
    const std::string f = e.path().filename().string();
    if (e.path().extension() == ".lcm" && f.rfind("snapnav_", 0) == 0) files.insert(f.substr(8, f.size() - 12));
  }
  for (const auto& t : types) names.insert(t.name);
  EXPECT_EQ(names, files);
  EXPECT_GE(types.size(), 13u);
  for (const auto& t : types) {
    const Outcome o = DecodeProbed(t, t.sample);
    ASSERT_TRUE(o.decoded) << t.name << ": " << o.error;
    EXPECT_TRUE(o.reencoded == t.sample) << t.name;
    EXPECT_GT(o.peak_bytes, 0u) << t.name << ": the allocation probe sees nothing";
  }
}

TEST(FuzzDecoders, TruncatedAtEveryLengthAndTrailingBytesAreRejected) {
  for (const auto& t : AllTypes()) {
    for (size_t n = 0; n < t.sample.size(); ++n) {
      const std::string cut = t.sample.substr(0, n);
      Check(t, cut, "truncated to " + std::to_string(n));
      EXPECT_FALSE(DecodeProbed(t, cut).decoded) << t.name << " truncated to " << n;
    }
    for (const char* tail : {"\0", "x", "\xED\xA1\xDA\x01"}) {
      const Outcome o = DecodeProbed(t, t.sample + std::string(tail, std::max<size_t>(1, std::strlen(tail))));
      EXPECT_FALSE(o.decoded) << t.name;
      EXPECT_NE(o.error.find("trailing"), std::string::npos) << t.name << ": " << o.error;
    }
  }
}

TEST(FuzzDecoders, WrongFingerprintsAreRejectedByName) {
  const auto types = AllTypes();
  for (const auto& t : types) {
    for (const auto& other : types) {
      if (other.name == t.name) continue;
      const Outcome o = DecodeProbed(t, other.sample);
      EXPECT_FALSE(o.decoded) << other.name << " decoded as " << t.name;
      EXPECT_NE(o.error.find("wrong type"), std::string::npos) << o.error;
    }
    for (int bit = 0; bit < 64; ++bit) {
      std::string b = t.sample;
      b[bit / 8] = static_cast<char>(b[bit / 8] ^ (1 << (bit % 8)));
      EXPECT_FALSE(DecodeProbed(t, b).decoded) << t.name << " fingerprint bit " << bit;
    }
  }
}

TEST(FuzzDecoders, AbsurdCountsAndNonFiniteValuesAtEveryOffset) {
  const std::vector<std::pair<uint64_t, int>> patterns = {
      {0x7fffffffu, 4}, {0x80000000u, 4}, {0xffffffffu, 4}, {0x40000000u, 4}, {0x00010000u, 4}, {0, 4},
      {FloatBits(NAN), 4}, {FloatBits(INFINITY), 4}, {FloatBits(-INFINITY), 4}, {FloatBits(3e38f), 4},
      {DoubleBits(NAN), 8}, {DoubleBits(INFINITY), 8}, {DoubleBits(-INFINITY), 8}, {DoubleBits(1e300), 8},
      {0x7fffffffffffffffull, 8}, {0x8000000000000000ull, 8}};
  int decoded = 0, rejected = 0;
  for (const auto& t : AllTypes()) {
    for (size_t at = 8; at < t.sample.size(); ++at) {
      for (const auto& [value, n] : patterns) {
        std::string b = t.sample;
        Put(&b, at, value, n);
        Check(t, b, "pattern " + std::to_string(value) + " at byte " + std::to_string(at));
        (DecodeProbed(t, b).decoded ? decoded : rejected) += 1;
      }
    }
  }
  // Both happen: NaN in a float field decodes (the nodes must reject it), a count does not.
  EXPECT_GT(decoded, 100);
  EXPECT_GT(rejected, 100);
}

TEST(FuzzDecoders, SeededRandomMutations) {
  std::mt19937_64 rng(0x5eed);
  for (const auto& t : AllTypes()) {
    for (int trial = 0; trial < 20000; ++trial) {
      std::string b = t.sample;
      const int edits = 1 + static_cast<int>(rng() % 4);
      for (int e = 0; e < edits; ++e) {
        const size_t at = 8 + rng() % (b.size() > 8 ? b.size() - 8 : 1);
        switch (rng() % 5) {
          case 0: if (at < b.size()) b[at] = static_cast<char>(b[at] ^ (1 << (rng() % 8))); break;
          case 1: if (at < b.size()) b[at] = static_cast<char>(rng()); break;
          case 2: b.insert(std::min(at, b.size()), 1, static_cast<char>(rng())); break;
          case 3: if (at < b.size()) b.erase(at, 1 + rng() % 8); break;
          case 4: if (at < b.size()) b[at] = static_cast<char>(rng() % 2 ? 0xff : 0x00); break;
        }
      }
      Check(t, b, "mutation " + std::to_string(trial));
    }
  }
}

TEST(FuzzDecoders, StringsThatCannotBeEncodedAgainAreRejected) {
  // A NUL inside a string or a missing terminator: LCM's encoder writes strlen() bytes, so
  // such a message would publish bytes it never wrote.
  for (const auto& t : AllTypes()) {
    if (t.name == "place_cell_match_t" || t.name == "fused_slam_status_t" || t.name == "laser_slam_status_t" ||
        t.name == "localization_status_t")
      continue;  // no string field (localization_status_t: its one string comes last)
    // The first string follows the fingerprint and utime (and an int8 in two types).
    const size_t len_at = t.name == "homing_vector_t" || t.name == "navigator_status_t" ? 17 : 16;
    int32_t len = 0;
    for (int k = 0; k < 4; ++k) len = (len << 8) | static_cast<uint8_t>(t.sample[len_at + k]);
    ASSERT_GE(len, 2) << t.name;
    ASSERT_EQ(t.sample[len_at + 4 + len - 1], '\0') << t.name;
    std::string inner = t.sample;
    inner[len_at + 4] = '\0';
    EXPECT_FALSE(DecodeProbed(t, inner).decoded) << t.name << ": NUL inside a string";
    std::string unterminated = t.sample;
    unterminated[len_at + 4 + len - 1] = 'x';
    EXPECT_FALSE(DecodeProbed(t, unterminated).decoded) << t.name << ": string without its NUL";
  }
}

}  // namespace
}  // namespace snapnav::fuzz
