#include "encode/transforms.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <numeric>

namespace treelobes::encode {

namespace {

std::vector<std::uint8_t> natural_table(unsigned alphabet_size) {
    std::vector<std::uint8_t> table(alphabet_size);
    std::iota(table.begin(), table.end(), std::uint8_t{0});
    return table;
}

}  // namespace

std::vector<std::uint8_t> mtf_encode(std::span<const std::uint8_t> symbols, unsigned alphabet_size) {
    std::vector<std::uint8_t> table = natural_table(alphabet_size);
    std::vector<std::uint8_t> out;
    out.reserve(symbols.size());
    for (std::uint8_t s : symbols) {
        const auto it = std::find(table.begin(), table.end(), s);
        if (it == table.end()) throw Error(ExitCode::Internal, "MTF symbol outside the alphabet");
        out.push_back(static_cast<std::uint8_t>(it - table.begin()));
        std::rotate(table.begin(), it, it + 1);
    }
    return out;
}

std::vector<std::uint8_t> mtf_decode(std::span<const std::uint8_t> positions, unsigned alphabet_size,
                                     const std::string& context) {
    std::vector<std::uint8_t> table = natural_table(alphabet_size);
    std::vector<std::uint8_t> out;
    out.reserve(positions.size());
    for (std::uint8_t p : positions) {
        if (p >= alphabet_size) throw Error::input(context, "move-to-front position " + std::to_string(p) + " outside the table");
        const auto it = table.begin() + p;
        out.push_back(*it);
        std::rotate(table.begin(), it, it + 1);
    }
    return out;
}

std::vector<std::uint64_t> cumulative_sum(std::span<const std::uint64_t> values) {
    std::vector<std::uint64_t> sums(values.size());
    std::partial_sum(values.begin(), values.end(), sums.begin());
    return sums;
}

std::vector<std::uint64_t> differences(std::span<const std::uint64_t> sums, std::uint64_t max_difference,
                                       const std::string& context) {
    std::vector<std::uint64_t> values(sums.size());
    std::uint64_t previous = 0;
    for (std::size_t i = 0; i < sums.size(); ++i) {
        if (sums[i] < previous || sums[i] - previous > max_difference)
            throw Error::input(context, "cumulative sum is not a valid sequence at element " + std::to_string(i));
        values[i] = sums[i] - previous;
        previous = sums[i];
    }
    return values;
}

}  // namespace treelobes::encode
