#pragma once
// Byte-level helpers shared by the C3D reader and writer (internal to csw_io_c3d).
#include <bit>
#include <cstdint>
#include <cstring>

namespace csw::c3d {

inline constexpr int kBlock = 512;
inline constexpr unsigned char kKey = 0x50;
inline constexpr int kProcessorBase = 83;  // processor byte = 83 + type

enum class Processor { kIntel = 1, kDec = 2, kMips = 3 };

inline uint16_t LoadU16Le(const unsigned char* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
inline uint16_t LoadU16Be(const unsigned char* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }
inline uint32_t LoadU32Le(const unsigned char* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}
inline uint32_t LoadU32Be(const unsigned char* p) {
  return (static_cast<uint32_t>(p[0]) << 24) | (static_cast<uint32_t>(p[1]) << 16) |
         (static_cast<uint32_t>(p[2]) << 8) | static_cast<uint32_t>(p[3]);
}

template <Processor kP>
inline uint16_t LoadU16(const unsigned char* p) {
  if constexpr (kP == Processor::kMips) {
    return LoadU16Be(p);
  } else {
    return LoadU16Le(p);
  }
}

template <Processor kP>
inline int16_t LoadI16(const unsigned char* p) {
  return static_cast<int16_t>(LoadU16<kP>(p));
}

// IEEE single (Intel little-endian, MIPS big-endian) or DEC VAX F-float: the DEC
// layout is the IEEE bit pattern with its 16-bit halves swapped and a value four
// times larger (exponent bias 128 with the hidden bit at 0.5).
template <Processor kP>
inline float LoadF32(const unsigned char* p) {
  if constexpr (kP == Processor::kIntel) {
    float v;
    std::memcpy(&v, p, 4);
    if constexpr (std::endian::native != std::endian::little) v = std::bit_cast<float>(LoadU32Le(p));
    return v;
  } else if constexpr (kP == Processor::kMips) {
    return std::bit_cast<float>(LoadU32Be(p));
  } else {
    uint32_t bits = static_cast<uint32_t>(LoadU16Le(p + 2)) | (static_cast<uint32_t>(LoadU16Le(p)) << 16);
    // A zero exponent is a true zero in VAX F-float (no denormals).
    if ((bits & 0x7F800000u) == 0) return 0.0f;
    return std::bit_cast<float>(bits) * 0.25f;
  }
}

inline uint16_t LoadU16(Processor proc, const unsigned char* p) {
  return proc == Processor::kMips ? LoadU16Be(p) : LoadU16Le(p);
}
inline int16_t LoadI16(Processor proc, const unsigned char* p) { return static_cast<int16_t>(LoadU16(proc, p)); }
inline float LoadF32(Processor proc, const unsigned char* p) {
  switch (proc) {
    case Processor::kDec:
      return LoadF32<Processor::kDec>(p);
    case Processor::kMips:
      return LoadF32<Processor::kMips>(p);
    case Processor::kIntel:
      break;
  }
  return LoadF32<Processor::kIntel>(p);
}

inline void StoreU16Le(unsigned char* p, uint16_t v) {
  p[0] = static_cast<unsigned char>(v & 0xFF);
  p[1] = static_cast<unsigned char>(v >> 8);
}
inline void StoreF32Le(unsigned char* p, float v) {
  uint32_t bits = std::bit_cast<uint32_t>(v);
  for (int i = 0; i < 4; ++i) p[i] = static_cast<unsigned char>((bits >> (8 * i)) & 0xFF);
}

}  // namespace csw::c3d
