// Seeded, stratified splits shared by JointBoost's early stopping, the XGBoost baseline and the
// evaluation protocol, so every classifier sees exactly the same trees in the same roles.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace treelobes::classify {

// Per class c with n_c trees: floor(fraction * n_c) of them, drawn at random, go to `first` and
// the rest to `second`; a class with two or more trees keeps at least one on each side, a class
// with one tree puts it in `first` only when `single_to_first`. Both outputs are sorted.
// Deterministic for (labels, seed) on every platform.
void stratified_split(const std::vector<int>& labels, int classes, double fraction, std::uint64_t seed, bool single_to_first,
                      std::vector<std::size_t>& first, std::vector<std::size_t>& second);

// Stratified K-fold assignment: per class, the trees in a seeded random order are dealt to folds
// 0, 1, ..., folds-1, 0, 1, ... (so fold sizes per class differ by at most one). Returns the fold
// of each row; deterministic for (labels, folds, seed).
std::vector<int> stratified_folds(const std::vector<int>& labels, int classes, int folds, std::uint64_t seed);

}  // namespace treelobes::classify
