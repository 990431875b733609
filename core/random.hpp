// The one random source of treelobes: synthetic trees and scans, stochastic L-systems, lobe
// texturing and patch libraries, classification splits. std:: distributions are
// implementation-defined (libstdc++ and libc++ give different numbers for the same engine), so the
// generator and the distributions are spelled out here: same seed -> same output on every platform.
#pragma once

#include <cmath>
#include <cstdint>

namespace treelobes {

// SplitMix64 (Steele, Lea, Flood 2014): used to derive independent streams from (seed, key).
inline std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

// Seed of an independent stream, e.g. stream_seed(tree_seed, pulse_index): parallel loops draw
// from per-item streams so the result does not depend on the thread schedule.
inline std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t key) {
    return splitmix64(seed ^ splitmix64(key + 0x632be59bd9b4e019ULL));
}

// xoshiro256** (Blackman & Vigna 2018).
class Rng {
public:
    explicit Rng(std::uint64_t seed) {
        std::uint64_t x = seed;
        for (auto& word : s_) word = x = splitmix64(x);
    }

    std::uint64_t next() {
        const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
        const std::uint64_t t = s_[1] << 17;
        s_[2] ^= s_[0];
        s_[3] ^= s_[1];
        s_[1] ^= s_[2];
        s_[0] ^= s_[3];
        s_[2] ^= t;
        s_[3] = rotl(s_[3], 45);
        return result;
    }

    // Uniform in [0, 1) with 53 random bits.
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    // Uniform in [-half_width, +half_width]: the "*_v" variations of the species profiles.
    double vary(double half_width) { return half_width * (2.0 * uniform() - 1.0); }
    // Standard normal by Box-Muller (one value per call; simple beats fast here).
    double normal() {
        double u1 = uniform();
        if (u1 < 1e-300) u1 = 1e-300;
        const double u2 = uniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
    }
    double normal(double mean, double sigma) { return mean + sigma * normal(); }
    // Integer in [0, n).
    std::uint64_t below(std::uint64_t n) { return n == 0 ? 0 : next() % n; }
    // Rounds x up or down at random so that the expectation is x (fractional counts).
    int stochastic_round(double x) {
        const double f = std::floor(x);
        return static_cast<int>(f) + (uniform() < x - f ? 1 : 0);
    }

private:
    static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    std::uint64_t s_[4];
};

}  // namespace treelobes
