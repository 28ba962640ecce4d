// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A test-side CDR writer built from the specification and independent of the code under test
// (CORBA 3.3 Part 2 §9.3 "CDR Transfer Syntax"; DDS-XTypes 1.3 §7.6.3.1.2 encapsulation header):
// the bags' messages and the ROS 2 node's wire types are checked against its bytes.

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace lidarcal::test {

/// CDR bytes: encapsulation header (0x0000 big-endian, 0x0001 little-endian, options 0), then
/// each primitive aligned on its size counted from the byte after the header.
class CdrWriter {
 public:
  explicit CdrWriter(bool big_endian) : big_(big_endian) {
    bytes_ = {'\0', big_endian ? '\0' : '\1', '\0', '\0'};
  }
  /// octet, uint8, char, bool: one byte, no alignment
  void u8(std::uint8_t v) { bytes_ += static_cast<char>(v); }
  /// a fixed array of octets (`char[N]`, `uint8[N]` in a .msg): the bytes, no length
  void octets(const std::vector<std::uint8_t>& v) { bytes_.append(v.begin(), v.end()); }
  void u32(std::uint32_t v) { put(v, 4); }
  void i32(std::int32_t v) { put(static_cast<std::uint32_t>(v), 4); }
  void f32(float v) {
    std::uint32_t b;
    std::memcpy(&b, &v, 4);
    put(b, 4);
  }
  void f64(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, 8);
    put(b, 8);
  }
  /// uint32 length counting the terminating NUL, the characters, the NUL (§9.3.2.7)
  void str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    bytes_ += s;
    bytes_ += '\0';
  }
  void f32seq(const std::vector<float>& v) {
    u32(static_cast<std::uint32_t>(v.size()));
    for (float x : v) f32(x);
  }
  const std::string& bytes() const { return bytes_; }

 private:
  void put(std::uint64_t v, int n) {
    while ((bytes_.size() - 4) % static_cast<std::size_t>(n)) bytes_ += '\0';
    for (int i = 0; i < n; ++i) bytes_ += static_cast<char>(v >> (8 * (big_ ? n - 1 - i : i)));
  }
  bool big_;
  std::string bytes_;
};

}  // namespace lidarcal::test
