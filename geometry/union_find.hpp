// Disjoint sets with path halving and union by size; used for connected components of the
// neighbour graph, of geodesic bins and of tree bases.
#pragma once

#include <numeric>
#include <vector>

namespace treelobes {

class UnionFind {
public:
    explicit UnionFind(std::size_t n) : parent_(n), size_(n, 1) { std::iota(parent_.begin(), parent_.end(), 0); }

    int find(int x) {
        while (parent_[x] != x) {
            parent_[x] = parent_[parent_[x]];
            x = parent_[x];
        }
        return x;
    }
    // Returns false when a and b were already in one set. The larger set's root survives
    // (the smaller index on ties), so the result does not depend on argument order.
    bool unite(int a, int b) {
        a = find(a);
        b = find(b);
        if (a == b) return false;
        if (size_[a] < size_[b] || (size_[a] == size_[b] && b < a)) std::swap(a, b);
        parent_[b] = a;
        size_[a] += size_[b];
        return true;
    }
    int set_size(int x) { return size_[find(x)]; }

private:
    std::vector<int> parent_;
    std::vector<int> size_;
};

}  // namespace treelobes
