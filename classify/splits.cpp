#include "classify/splits.hpp"

#include "core/random.hpp"

#include <algorithm>
#include <cmath>

namespace treelobes::classify {

void stratified_split(const std::vector<int>& labels, int classes, double fraction, std::uint64_t seed, bool single_to_first,
                      std::vector<std::size_t>& first, std::vector<std::size_t>& second) {
    first.clear();
    second.clear();
    std::vector<std::vector<std::size_t>> by_class(classes);
    for (std::size_t i = 0; i < labels.size(); ++i) by_class[labels[i]].push_back(i);
    Rng rng(stream_seed(seed, 0x5b1175));
    for (auto& members : by_class) {
        for (std::size_t i = members.size(); i > 1; --i) std::swap(members[i - 1], members[rng.below(i)]);  // Fisher-Yates
        const std::size_t n = members.size();
        std::size_t take = static_cast<std::size_t>(std::floor(fraction * static_cast<double>(n) + 1e-9));
        if (n >= 2)
            take = std::clamp<std::size_t>(take, 1, n - 1);
        else
            take = single_to_first ? n : 0;
        first.insert(first.end(), members.begin(), members.begin() + static_cast<std::ptrdiff_t>(take));
        second.insert(second.end(), members.begin() + static_cast<std::ptrdiff_t>(take), members.end());
    }
    std::sort(first.begin(), first.end());
    std::sort(second.begin(), second.end());
}

std::vector<int> stratified_folds(const std::vector<int>& labels, int classes, int folds, std::uint64_t seed) {
    std::vector<std::vector<std::size_t>> by_class(classes);
    for (std::size_t i = 0; i < labels.size(); ++i) by_class[labels[i]].push_back(i);
    Rng rng(stream_seed(seed, 0xf01d5));
    std::vector<int> fold(labels.size(), 0);
    int next = 0;  // continue dealing across classes so small classes do not all start in fold 0
    for (auto& members : by_class) {
        for (std::size_t i = members.size(); i > 1; --i) std::swap(members[i - 1], members[rng.below(i)]);
        for (std::size_t i : members) fold[i] = next, next = (next + 1) % folds;
    }
    return fold;
}

}  // namespace treelobes::classify
