#pragma once
// Decoding of LCM payloads into generated types with a reason on failure.

#include <cstdint>
#include <cstring>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>

namespace snapnav::glue {

// Reads the 8-byte big-endian type fingerprint at the start of an LCM payload.
inline std::optional<uint64_t> PayloadFingerprint(const void* data, size_t size) {
  if (size < 8) return std::nullopt;
  const auto* b = static_cast<const uint8_t*>(data);
  uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | b[i];
  return h;
}

// Decodes `size` bytes into a Msg. Returns std::nullopt and sets *error to the
// reason when the payload is of another type, truncated, corrupt, or has
// trailing bytes. Never throws for bad input.
template <class Msg>
std::optional<Msg> Decode(const void* data, size_t size, std::string* error) {
  auto fail = [&](const std::string& why) -> std::optional<Msg> {
    if (error) *error = why;
    return std::nullopt;
  };
  const auto fingerprint = PayloadFingerprint(data, size);
  if (!fingerprint) {
    return fail("payload of " + std::to_string(size) + " bytes is shorter than a type fingerprint");
  }
  if (*fingerprint != static_cast<uint64_t>(Msg::getHash())) {
    return fail(std::string("wrong type: payload fingerprint does not match ") + Msg::getTypeName());
  }
  if (size > static_cast<size_t>(INT32_MAX)) return fail("payload larger than 2 GiB");
  Msg msg;
  int used = -1;
  try {
    used = msg.decode(data, 0, static_cast<int>(size));
  } catch (const std::exception& e) {  // e.g. std::bad_alloc, std::length_error
    return fail(std::string("decode of ") + Msg::getTypeName() + " failed: " + e.what());
  }
  if (used < 0) {
    return fail(std::string("truncated or corrupt ") + Msg::getTypeName() + " payload (" +
                std::to_string(size) + " bytes)");
  }
  if (static_cast<size_t>(used) != size) {
    return fail(std::string(Msg::getTypeName()) + " payload has " + std::to_string(size - used) +
                " trailing bytes");
  }
  return msg;
}

// Encodes a message into a byte string (for tests, logs and raw republishing).
template <class Msg>
std::string Encode(const Msg& msg) {
  const int n = msg.getEncodedSize();
  std::string out(static_cast<size_t>(n), '\0');
  if (msg.encode(out.data(), 0, n) != n) {
    throw std::runtime_error(std::string("cannot encode ") + Msg::getTypeName());
  }
  return out;
}

}  // namespace snapnav::glue
