#include "encode/bwt.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <numeric>

namespace treelobes::encode {

namespace {

// One counting-sort pass: orders `items` stably by key[item] (keys < key_count).
void counting_sort(const std::vector<std::uint32_t>& items, const std::vector<std::uint32_t>& key, std::size_t key_count,
                   std::vector<std::uint32_t>& out) {
    std::vector<std::uint32_t> start(key_count + 1, 0);
    for (std::uint32_t item : items) ++start[key[item] + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    for (std::uint32_t item : items) out[start[key[item]]++] = item;
}

}  // namespace

// Prefix doubling on the cyclic shifts of text$ (the sentinel makes cyclic order equal suffix
// order). After round h the shifts are sorted by their first 2^h symbols; classes[i] is the
// rank of shift i's prefix. Stops as soon as every class is distinct.
std::vector<std::uint32_t> suffix_array(std::span<const std::uint8_t> text, unsigned alphabet_size) {
    const std::size_t n = text.size() + 1;  // with the sentinel
    if (n > UINT32_MAX) throw Error(ExitCode::Internal, "suffix array input too long");
    std::vector<std::uint32_t> classes(n), order(n), shifted(n), next_classes(n);
    for (std::size_t i = 0; i + 1 < n; ++i) {
        if (text[i] >= alphabet_size) throw Error(ExitCode::Internal, "symbol outside the alphabet");
        classes[i] = text[i] + 1u;
    }
    classes[n - 1] = 0;  // sentinel
    std::vector<std::uint32_t> identity(n);
    std::iota(identity.begin(), identity.end(), 0u);
    counting_sort(identity, classes, alphabet_size + 1, order);
    std::size_t class_count = alphabet_size + 1;
    for (std::size_t h = 1;; h <<= 1) {
        // Sorting by (class[i], class[i + h]): the shifts i - h, taken in the current order,
        // are already sorted by their second half, so one stable pass by the first half suffices.
        for (std::size_t k = 0; k < n; ++k) shifted[k] = static_cast<std::uint32_t>((order[k] + n - h % n) % n);
        counting_sort(shifted, classes, class_count, order);
        next_classes[order[0]] = 0;
        std::uint32_t rank = 0;
        for (std::size_t k = 1; k < n; ++k) {
            const std::uint32_t a = order[k - 1], b = order[k];
            if (classes[a] != classes[b] || classes[(a + h) % n] != classes[(b + h) % n]) ++rank;
            next_classes[b] = rank;
        }
        classes.swap(next_classes);
        class_count = rank + 1;
        if (class_count == n || h >= n) break;
    }
    return order;
}

BwtResult bwt_forward(std::span<const std::uint8_t> text, unsigned alphabet_size) {
    const std::vector<std::uint32_t> sa = suffix_array(text, alphabet_size);
    BwtResult result;
    result.last_column.reserve(text.size());
    for (std::size_t row = 0; row < sa.size(); ++row) {
        if (sa[row] == 0)
            result.primary_index = row;  // the sentinel precedes the whole text
        else
            result.last_column.push_back(text[sa[row] - 1]);
    }
    return result;
}

// Walks the LF mapping from row 0 (the rotation "$text"), emitting the text backwards.
std::vector<std::uint8_t> bwt_inverse(std::span<const std::uint8_t> last_column, std::size_t primary_index, unsigned alphabet_size,
                                      const std::string& context) {
    const std::size_t n = last_column.size();
    if (primary_index > n)
        throw Error::input(context, "BWT primary index " + std::to_string(primary_index) + " beyond the " + std::to_string(n) + " symbols");
    std::vector<std::size_t> first_row(alphabet_size + 1, 1);  // row 0 belongs to the sentinel
    std::vector<std::size_t> counts(alphabet_size, 0);
    for (std::uint8_t s : last_column) {
        if (s >= alphabet_size) throw Error::input(context, "BWT symbol " + std::to_string(s) + " outside the alphabet");
        ++counts[s];
    }
    for (unsigned s = 0; s < alphabet_size; ++s) first_row[s + 1] = first_row[s] + counts[s];
    // lf[row] for the n + 1 rows; the sentinel's row is never followed.
    std::vector<std::uint32_t> lf(n + 1, 0);
    std::vector<std::size_t> seen(alphabet_size, 0);
    for (std::size_t row = 0, k = 0; row <= n; ++row) {
        if (row == primary_index) continue;
        const std::uint8_t s = last_column[k++];
        lf[row] = static_cast<std::uint32_t>(first_row[s] + seen[s]++);
    }
    std::vector<std::uint8_t> text(n);
    std::size_t row = 0;
    for (std::size_t i = n; i-- > 0;) {
        if (row == primary_index) throw Error::input(context, "BWT primary index does not invert the transform");
        text[i] = last_column[row < primary_index ? row : row - 1];
        row = lf[row];
    }
    if (row != primary_index) throw Error::input(context, "BWT primary index does not invert the transform");
    return text;
}

}  // namespace treelobes::encode
