#include "encode/interpolative.hpp"

#include "core/error.hpp"

namespace treelobes::encode {

namespace {

struct Range {
    std::uint64_t low, high;
};

// Saturating a + k*g and a - k*g: the gap bound may be "unbounded".
std::uint64_t add_steps(std::uint64_t a, std::uint64_t steps, std::uint64_t gap) {
    if (gap != 0 && steps > (kNoGapBound - a) / gap) return kNoGapBound;
    return a + steps * gap;
}
std::uint64_t sub_steps(std::uint64_t a, std::uint64_t steps, std::uint64_t gap) {
    if (gap != 0 && steps > a / gap) return 0;
    return a - steps * gap;
}

// Possible values of element m given the values at a and b (a < m < b).
Range middle_range(std::size_t a, std::uint64_t left, std::size_t m, std::size_t b, std::uint64_t right, std::uint64_t max_gap) {
    Range r{left, right};
    if (max_gap != kNoGapBound) {
        r.low = std::max(r.low, sub_steps(right, b - m, max_gap));
        r.high = std::min(r.high, add_steps(left, m - a, max_gap));
    }
    return r;
}

unsigned fixed_bits(std::uint64_t n) { return n <= 1 ? 0 : bit_width64(n - 1); }

void write_value(BitWriter& out, std::uint64_t x, std::uint64_t n, MiddleCode code) {
    if (code == MiddleCode::FixedBinary)
        out.write(x, fixed_bits(n));
    else
        write_centred_minimal_binary(out, x, n);
}

std::uint64_t read_value(BitReader& in, std::uint64_t n, MiddleCode code) {
    if (code == MiddleCode::CentredMinimalBinary) return read_centred_minimal_binary(in, n);
    const std::uint64_t x = in.read(fixed_bits(n));
    if (x >= n) in.fail("interpolative value outside its range");
    return x;
}

void write_recursive(BitWriter& out, std::span<const std::uint64_t> v, std::size_t a, std::size_t b, const InterpolativeOptions& o,
                     std::vector<InterpolativeStep>* trace) {
    if (b - a < 2) return;
    const std::size_t m = a + (b - a) / 2;
    const Range r = middle_range(a, v[a], m, b, v[b], o.max_gap);
    if (v[m] < r.low || v[m] > r.high)
        throw Error(ExitCode::Internal, "interpolative coding: sequence is not non-decreasing within the gap bound");
    const std::uint64_t n = r.high - r.low + 1;
    const std::size_t before = out.bit_count();
    write_value(out, v[m] - r.low, n, o.middle_code);
    if (trace) trace->push_back({m, r.low, r.high, static_cast<unsigned>(out.bit_count() - before)});
    write_recursive(out, v, a, m, o, trace);
    write_recursive(out, v, m, b, o, trace);
}

void read_recursive(BitReader& in, std::span<std::uint64_t> v, std::size_t a, std::size_t b, const InterpolativeOptions& o) {
    if (b - a < 2) return;
    const std::size_t m = a + (b - a) / 2;
    const Range r = middle_range(a, v[a], m, b, v[b], o.max_gap);
    if (r.low > r.high) in.fail("interpolative bounds are inconsistent (corrupt stream)");
    if (r.high - r.low == kNoGapBound) in.fail("interpolative range too large (corrupt stream)");
    v[m] = r.low + read_value(in, r.high - r.low + 1, o.middle_code);
    // Runs of equal ends decode without reading a bit; a whole run can be filled at once.
    if (v[a] == v[b]) {
        for (std::size_t i = a + 1; i < b; ++i) v[i] = v[a];
        return;
    }
    read_recursive(in, v, a, m, o);
    read_recursive(in, v, m, b, o);
}

}  // namespace

void write_interpolative_between(BitWriter& out, std::span<const std::uint64_t> values, std::size_t first, std::size_t last,
                                 const InterpolativeOptions& options, std::vector<InterpolativeStep>* trace) {
    if (first > last || last >= values.size()) throw Error(ExitCode::Internal, "interpolative coding: bad positions");
    write_recursive(out, values, first, last, options, trace);
}

void read_interpolative_between(BitReader& in, std::span<std::uint64_t> values, std::size_t first, std::size_t last,
                                const InterpolativeOptions& options) {
    if (first > last || last >= values.size()) throw Error(ExitCode::Internal, "interpolative decoding: bad positions");
    read_recursive(in, values, first, last, options);
}

void write_interpolative(BitWriter& out, std::span<const std::uint64_t> values, const InterpolativeOptions& options) {
    if (values.empty()) return;
    std::vector<std::uint64_t> padded(values.size() + 1, 0);  // virtual element 0 in front
    std::copy(values.begin(), values.end(), padded.begin() + 1);
    write_count(out, padded.back());
    write_recursive(out, padded, 0, padded.size() - 1, options, nullptr);
}

std::vector<std::uint64_t> read_interpolative(BitReader& in, std::size_t n, const InterpolativeOptions& options) {
    if (n == 0) return {};
    std::vector<std::uint64_t> padded(n + 1, 0);
    padded.back() = read_count(in);
    if (options.max_gap != kNoGapBound && padded.back() > add_steps(0, n, options.max_gap))
        in.fail("interpolative sequence ends beyond its gap bound");
    read_recursive(in, padded, 0, n, options);
    return {padded.begin() + 1, padded.end()};
}

}  // namespace treelobes::encode
