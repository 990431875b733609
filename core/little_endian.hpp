// Little-endian field access for binary formats (LAS, LAZ, COPC). Assembling the bytes keeps the
// code independent of the host's byte order.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

namespace treelobes {

namespace detail {
template <std::size_t N>
struct UnsignedOfSize;
template <>
struct UnsignedOfSize<1> {
    using type = std::uint8_t;
};
template <>
struct UnsignedOfSize<2> {
    using type = std::uint16_t;
};
template <>
struct UnsignedOfSize<4> {
    using type = std::uint32_t;
};
template <>
struct UnsignedOfSize<8> {
    using type = std::uint64_t;
};
}  // namespace detail

template <typename T>
T load(const std::uint8_t* p) {
    using U = typename detail::UnsignedOfSize<sizeof(T)>::type;
    std::uint64_t bits = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) bits |= std::uint64_t{p[i]} << (8 * i);
    return std::bit_cast<T>(static_cast<U>(bits));
}

template <typename T>
void store(std::uint8_t* p, T value) {
    using U = typename detail::UnsignedOfSize<sizeof(T)>::type;
    const auto bits = static_cast<std::uint64_t>(std::bit_cast<U>(value));
    for (std::size_t i = 0; i < sizeof(T); ++i) p[i] = static_cast<std::uint8_t>(bits >> (8 * i));
}

}  // namespace treelobes
