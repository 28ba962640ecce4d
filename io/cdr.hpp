// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A reader of OMG CDR (Common Data Representation), the serialisation of ROS 2 messages: a
// 4-byte encapsulation header, then the fields in declaration order, each primitive aligned on
// its own size relative to the first byte after that header. Bounds-checked: every read that
// would run past the end throws InputError (item "byte N"), never reads out of bounds.
//
// References: CORBA 3.3 Part 2 (formal/2012-11-14) §9.3 "CDR Transfer Syntax": §9.3.1.1
// alignment, §9.3.2.5 sequences, §9.3.2.7 strings; DDS-XTypes 1.3 §7.6.3.1.2 encapsulation
// identifiers (CDR_BE = 0x0000, CDR_LE = 0x0001), as RTPS and ROS 2 (rmw) write them.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lidarcal::io {

class CdrReader {
 public:
  /// Reads the encapsulation header of `size` bytes at `data` (not copied: they must outlive the
  /// reader). Throws InputError unless it is plain CDR, big- or little-endian.
  CdrReader(const std::uint8_t* data, std::size_t size);

  bool bigEndian() const { return big_endian_; }
  /// Bytes read so far, counted from the start of the data (encapsulation header included).
  std::size_t offset() const { return pos_; }

  std::uint8_t u8();  ///< an octet, uint8, char or bool (no alignment)
  /// A fixed array of `n` octets (e.g. `char[16]` of a .msg): no alignment, no length.
  std::vector<std::uint8_t> octets(std::size_t n);
  std::uint32_t u32();
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  float f32();
  double f64();
  /// A string: uint32 length including the terminating NUL, then the characters (§9.3.2.7).
  std::string str();
  /// A sequence<float32>: uint32 count, then the values (§9.3.2.5). The count is checked against
  /// the bytes left before anything is allocated.
  void f32Seq(std::vector<float>& out);
  /// A sequence's element count, checked against the bytes left for elements of at least
  /// `min_element_bytes`.
  std::uint32_t count(std::size_t min_element_bytes);

 private:
  void align(std::size_t n);
  const std::uint8_t* take(std::size_t n);
  std::uint64_t raw(std::size_t n);
  [[noreturn]] void fail(const std::string& problem) const;

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  bool big_endian_ = false;
};

}  // namespace lidarcal::io
