// Level of detail directly on the chain code (Strnad et al. 2020, §3.2, Pseudocode 2, Fig. 7).
//
// Every lateral branch whose first internode has a radius below the threshold T is removed
// with everything that grows on it; the fork symbol of its surviving parent becomes 8. The
// trunk and all main extensions are never shortened. Works on F6 and DBF6 alike: a removed
// lateral's first internode is coded fully, and the internode after a fork turned into 8 keeps
// its correction relative to the same predecessor.
//
// One deliberate difference from Pseudocode 2 as printed: a branch whose parent branch was
// removed is removed too, even when its own radius reaches T (the printed loop would copy it
// without the fork that attaches it, leaving an undecodable code).
#pragma once

#include "encode/chain_code.hpp"

#include <string>
#include <vector>

namespace treelobes::encode {

// C', R' of Pseudocode 2 for threshold T (in radius units). Throws Error(InvalidInput) naming
// `context` for a corrupt code or a radius list of the wrong length.
ChainCode reduce_lod(const ChainCode& code, double threshold, const std::string& context = "chain code");

// The thickness of every lateral branch, in code order: the radius of its first internode, the
// value Pseudocode 2 compares with T. Reads as much of a damaged code as it can.
std::vector<int> branch_thicknesses(const ChainCode& code);

// Thresholds for `levels` LODs (LOD 0 = full detail) as in §4 Experiment 1: the values at
// levels-1 uniformly spaced positions i*n/levels (i = 1..levels-1) of the n sorted unique branch
// thicknesses (branch_thicknesses; the trunk's radii, never pruned, would put the upper
// thresholds above every lateral and make those LODs the same). Non-decreasing; fewer unique
// values than levels repeat values. Throws Error(Usage) for levels < 1.
std::vector<double> lod_thresholds(const std::vector<int>& thicknesses, int levels);

// LOD 0..thresholds.size(): the full code, then successive reductions (each from the previous
// one, which equals reducing the full code by the larger threshold).
std::vector<ChainCode> lod_chain(const ChainCode& code, const std::vector<double>& thresholds, const std::string& context = "chain code");

}  // namespace treelobes::encode
