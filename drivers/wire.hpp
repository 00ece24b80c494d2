#pragma once
// Little-endian loads and stores for the wire format (docs/device-protocol.md §2: every
// multi-byte field is little-endian). memcpy keeps them free of alignment and aliasing
// problems; on a little-endian host they compile to plain moves.

#include <bit>
#include <cstdint>
#include <cstring>
#include <utility>

namespace springscan::drivers::wire {

template <typename T>
inline T load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
    auto* b = reinterpret_cast<std::uint8_t*>(&v);
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  return v;
}

template <typename T>
inline void store(std::uint8_t* p, T v) {
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
    auto* b = reinterpret_cast<std::uint8_t*>(&v);
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  std::memcpy(p, &v, sizeof v);
}

inline std::uint16_t load_u16(const std::uint8_t* p) { return load<std::uint16_t>(p); }
inline std::uint32_t load_u32(const std::uint8_t* p) { return load<std::uint32_t>(p); }
inline std::uint64_t load_u64(const std::uint8_t* p) { return load<std::uint64_t>(p); }
inline float load_f32(const std::uint8_t* p) { return load<float>(p); }
inline double load_f64(const std::uint8_t* p) { return load<double>(p); }
inline void store_u16(std::uint8_t* p, std::uint16_t v) { store(p, v); }
inline void store_u32(std::uint8_t* p, std::uint32_t v) { store(p, v); }
inline void store_u64(std::uint8_t* p, std::uint64_t v) { store(p, v); }
inline void store_f32(std::uint8_t* p, float v) { store(p, v); }
inline void store_f64(std::uint8_t* p, double v) { store(p, v); }

}  // namespace springscan::drivers::wire
