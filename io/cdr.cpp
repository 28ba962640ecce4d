// SPDX-License-Identifier: BSD-3-Clause
#include "io/cdr.hpp"

#include <cstdio>
#include <cstring>

#include "common/errors.hpp"

namespace lidarcal::io {
namespace {
constexpr std::size_t kHeaderBytes = 4;  // encapsulation identifier (2 bytes) + options (2 bytes)
}  // namespace

CdrReader::CdrReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {
  if (size < kHeaderBytes) fail("shorter than the 4-byte CDR encapsulation header");
  // DDS-XTypes 1.3 §7.6.3.1.2: the identifier is two bytes, big-endian; the options that follow
  // are ignored by readers.
  const unsigned id = (static_cast<unsigned>(data[0]) << 8) | data[1];
  if (id != 0x0000 && id != 0x0001) {
    char text[120];
    std::snprintf(
        text, sizeof text,
        "encapsulation 0x%04x is not plain CDR (0x0000 big-endian or 0x0001 little-endian)", id);
    fail(text);
  }
  big_endian_ = id == 0x0000;
  pos_ = kHeaderBytes;
}

void CdrReader::fail(const std::string& problem) const {
  throw InputError("", "byte " + std::to_string(pos_) + " of " + std::to_string(size_), problem);
}

// §9.3.1.1: a primitive of n bytes starts at a multiple of n, counted (in RTPS/ROS 2) from the
// first byte after the encapsulation header. The padding bytes are skipped unread.
void CdrReader::align(std::size_t n) {
  const std::size_t misalign = (pos_ - kHeaderBytes) % n;
  if (misalign) take(n - misalign);
}

const std::uint8_t* CdrReader::take(std::size_t n) {
  if (n > size_ - pos_)
    fail("the message ends here (" + std::to_string(n) +
         " more bytes expected): it is cut short or not this type");
  const std::uint8_t* p = data_ + pos_;
  pos_ += n;
  return p;
}

std::uint64_t CdrReader::raw(std::size_t n) {
  align(n);
  const std::uint8_t* p = take(n);
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = big_endian_ ? i : n - 1 - i;  // most significant byte first
    v = (v << 8) | p[k];
  }
  return v;
}

std::uint8_t CdrReader::u8() { return *take(1); }

std::vector<std::uint8_t> CdrReader::octets(std::size_t n) {
  const std::uint8_t* p = take(n);
  return {p, p + n};
}

std::uint32_t CdrReader::u32() { return static_cast<std::uint32_t>(raw(4)); }

float CdrReader::f32() {
  const std::uint32_t bits = u32();
  float v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

double CdrReader::f64() {
  const std::uint64_t bits = raw(8);
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::string CdrReader::str() {
  const std::uint32_t n = u32();
  if (n > size_ - pos_)
    fail("a string of " + std::to_string(n) + " bytes runs past the end of the message");
  const char* p = reinterpret_cast<const char*>(take(n));
  // The length counts the terminating NUL; a writer that leaves it out (length 0 for "") is
  // tolerated.
  return std::string(p, n > 0 && p[n - 1] == '\0' ? n - 1 : n);
}

std::uint32_t CdrReader::count(std::size_t min_element_bytes) {
  const std::uint32_t n = u32();
  if (min_element_bytes > 0 && n > (size_ - pos_) / min_element_bytes)
    fail("a sequence of " + std::to_string(n) + " elements runs past the end of the message");
  return n;
}

void CdrReader::f32Seq(std::vector<float>& out) {
  const std::uint32_t n = count(4);
  align(4);
  const std::uint8_t* p = take(static_cast<std::size_t>(n) * 4);
  out.resize(n);
  for (std::uint32_t i = 0; i < n; ++i, p += 4) {
    std::uint32_t bits = 0;
    for (int b = 0; b < 4; ++b) bits = (bits << 8) | p[big_endian_ ? b : 3 - b];
    std::memcpy(&out[i], &bits, sizeof bits);
  }
}

}  // namespace lidarcal::io
