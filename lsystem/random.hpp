// Deterministic random numbers for stochastic L-systems. The generator and the distributions are
// spelled out (std:: distributions differ between standard libraries), so the same seed gives the
// same derivation on every platform.
#pragma once

#include <cmath>
#include <cstdint>

namespace treelobes::lsystem {

// SplitMix64 (Steele, Lea, Flood 2014): tiny, full-period, and good enough for choosing rules.
class Random {
public:
    explicit Random(std::uint64_t seed) : state_(seed) {}

    std::uint64_t next() {
        std::uint64_t x = (state_ += 0x9e3779b97f4a7c15ULL);
        x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
        x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
        return x ^ (x >> 31);
    }
    // Uniform in [0, 1) with 53 random bits.
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    // Box-Muller; one value per call (two uniforms).
    double normal(double mean, double sigma) {
        const double u1 = 1.0 - uniform();  // (0, 1]: log stays finite
        const double u2 = uniform();
        return mean + sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
    }

private:
    std::uint64_t state_;
};

}  // namespace treelobes::lsystem
