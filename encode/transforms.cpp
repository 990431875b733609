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

// Moves the symbol at `position` up by `rule`; `previous` is the position coded before it.
void move_up(std::vector<std::uint8_t>& table, std::size_t position, std::size_t previous, MtfRule rule) {
    std::size_t target = 0;
    if (rule == MtfRule::Mtf2 && position > 0) target = position == 1 ? (previous != 0 ? 0 : 1) : 1;
    const auto it = table.begin() + static_cast<std::ptrdiff_t>(position);
    std::rotate(table.begin() + static_cast<std::ptrdiff_t>(target), it, it + 1);
}

}  // namespace

std::vector<std::uint8_t> mtf_encode(std::span<const std::uint8_t> symbols, unsigned alphabet_size, MtfRule rule) {
    std::vector<std::uint8_t> table = natural_table(alphabet_size);
    std::vector<std::uint8_t> out;
    out.reserve(symbols.size());
    std::size_t previous = 0;
    for (std::uint8_t s : symbols) {
        const auto it = std::find(table.begin(), table.end(), s);
        if (it == table.end()) throw Error(ExitCode::Internal, "MTF symbol outside the alphabet");
        const auto position = static_cast<std::size_t>(it - table.begin());
        out.push_back(static_cast<std::uint8_t>(position));
        move_up(table, position, previous, rule);
        previous = position;
    }
    return out;
}

std::vector<std::uint8_t> mtf_decode(std::span<const std::uint8_t> positions, unsigned alphabet_size, const std::string& context,
                                     MtfRule rule) {
    std::vector<std::uint8_t> table = natural_table(alphabet_size);
    std::vector<std::uint8_t> out;
    out.reserve(positions.size());
    std::size_t previous = 0;
    for (std::uint8_t p : positions) {
        if (p >= alphabet_size) throw Error::input(context, "move-to-front position " + std::to_string(p) + " outside the table");
        out.push_back(table[p]);
        move_up(table, p, previous, rule);
        previous = p;
    }
    return out;
}

std::vector<std::uint64_t> cumulative_sum(std::span<const std::uint64_t> values) {
    std::vector<std::uint64_t> sums(values.size());
    std::partial_sum(values.begin(), values.end(), sums.begin());
    return sums;
}

std::vector<std::uint64_t> differences(std::span<const std::uint64_t> sums, std::uint64_t max_difference, const std::string& context) {
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
