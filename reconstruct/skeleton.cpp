#include "reconstruct/skeleton.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/ransac_fit.hpp"
#include "geometry/shortest_paths.hpp"
#include "geometry/union_find.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>

namespace treelobes {

namespace {

void check_options(const SkeletonOptions& o) {
    auto non_negative = [](float v, const char* what) {
        if (!(v >= 0.0f) || !std::isfinite(v)) throw Error::usage(std::string("skeleton: ") + what + " must be >= 0");
    };
    non_negative(o.bin_width, "bin width");
    non_negative(o.internode_length, "internode length");
    non_negative(o.min_twig_length, "minimum twig length");
    non_negative(o.merge_distance, "merge distance");
    non_negative(o.max_edge_length, "maximum edge length");
    if (!(o.fine_bin_factor > 0.0f && o.fine_bin_factor <= 1.0f)) throw Error::usage("skeleton: fine bin factor must be in (0, 1]");
    non_negative(o.thick_slice, "thick slice");
    if (o.smoothing_iterations < 0 || o.smoothing_iterations > 100) throw Error::usage("skeleton: smoothing iterations must be in 0..100");
    if (o.max_gap_points < 0) throw Error::usage("skeleton: maximum points of a piece left out beyond a gap must be >= 0");
    if (o.max_gap_points > 0 && !(o.max_gap > 0))  // the size limit alone would silently do nothing
        throw Error::usage("skeleton: --max-gap-points needs --max-gap (the gap length beyond which pieces are left out)");
}

float median_nearest_distance(const NeighbourGraph& g) {
    std::vector<float> nearest;
    nearest.reserve(g.vertex_count());
    for (std::size_t i = 0; i < g.vertex_count(); ++i) {
        if (g.offsets[i] == g.offsets[i + 1]) continue;
        nearest.push_back(*std::min_element(g.lengths.begin() + g.offsets[i], g.lengths.begin() + g.offsets[i + 1]));
    }
    if (nearest.empty()) return 0.0f;
    auto mid = nearest.begin() + static_cast<long>(nearest.size() / 2);
    std::nth_element(nearest.begin(), mid, nearest.end());
    return *mid;
}

// Typical distance between neighbouring samples on the bark, from the median distance d6 to the
// 6th neighbour: on a surface sampled with density rho, d6 = sqrt(6 / (pi rho)), so the
// sampling distance 1/sqrt(rho) is d6 sqrt(pi / 6). The nearest-neighbour distance is not
// used: random sampling makes it half the sampling distance, regular TLS grids nearly all of it.
float sampling_distance(const KnnTable& near) {
    std::vector<float> d6;
    const std::size_t n = near.indices.size() / static_cast<std::size_t>(near.k);
    d6.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (near.row(i)[5] >= 0) d6.push_back(near.row_distances(i)[5]);
    if (d6.empty()) return 0.0f;
    auto mid = d6.begin() + static_cast<long>(d6.size() / 2);
    std::nth_element(d6.begin(), mid, d6.end());
    return std::sqrt(*mid) * std::sqrt(std::numbers::pi_v<float> / 6.0f);
}

// Bin clusters: connected pieces of the points that share a geodesic bin.
struct Clusters {
    std::vector<int> of_point;
    std::vector<int> parent;  // parent cluster; -1 = hangs from the root node
    std::vector<int> bin;
    std::vector<Eigen::Vector3d> sum;
    std::vector<double> sum_sq;  // of squared norms, for the spread
    std::vector<int> count;
    std::size_t size() const { return parent.size(); }
    Eigen::Vector3d centroid(int c) const { return sum[c] / static_cast<double>(count[c]); }
    // RMS distance of the points from their centroid: about the branch radius for a slice of
    // a thick branch, about w / sqrt(12) for a thin one.
    double spread(int c) const { return std::sqrt(std::max(0.0, sum_sq[c] / static_cast<double>(count[c]) - centroid(c).squaredNorm())); }
};

// Even the geodesic distance on a kNN graph is ragged by a few per cent between neighbours
// (each path zigzags its own way), which would cut a branch's cross-section into arcs lying in
// different bins. A few passes of neighbour averaging make the level sets clean cross-sections.
std::vector<float> smoothed_lengths(const NeighbourGraph& graph, const std::vector<float>& length, int passes) {
    std::vector<float> current = length, next(length.size());
    for (int pass = 0; pass < passes; ++pass) {
        for (std::size_t i = 0; i < current.size(); ++i) {
            double sum = current[i];
            for (std::uint32_t e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e) sum += current[graph.targets[e]];
            next[i] = static_cast<float>(sum / static_cast<double>(1 + graph.offsets[i + 1] - graph.offsets[i]));
        }
        current.swap(next);
    }
    return current;
}

// The parent of a cluster is where the weighted shortest-path tree (Livny et al. 2011: weights
// ||u-v||^beta) mostly enters it from: every point whose tree parent lies in an earlier
// cluster of a lower bin votes for that cluster. A majority is robust where single paths are
// not (one path may arrive through a small fragment of bark). Clusters that receive no vote
// (reached across a bridge or through the smoothing) hang from the cluster holding the
// geodesic parent of their first point.
std::vector<int> cluster_parents(const Clusters& c, const std::vector<int>& first_point, const ShortestPaths& geodesic,
                                 const ShortestPaths& weighted) {
    std::vector<std::pair<int, int>> votes;  // (cluster, voted parent)
    for (std::size_t u = 0; u < c.of_point.size(); ++u) {
        const int w = weighted.parent[u];
        if (w < 0) continue;
        const int a = c.of_point[u], b = c.of_point[w];
        if (a >= 0 && b >= 0 && b < a && c.bin[b] < c.bin[a]) votes.emplace_back(a, b);
    }
    std::sort(votes.begin(), votes.end());
    std::vector<int> parent(c.bin.size(), -1);
    std::vector<std::size_t> best(c.bin.size(), 0);
    for (std::size_t i = 0; i < votes.size();) {
        std::size_t j = i;
        while (j < votes.size() && votes[j] == votes[i]) ++j;
        if (j - i > best[votes[i].first]) {  // ties: the smaller cluster number (sorted first)
            best[votes[i].first] = j - i;
            parent[votes[i].first] = votes[i].second;
        }
        i = j;
    }
    for (std::size_t k = 0; k < parent.size(); ++k)
        if (best[k] == 0) {
            const int up = geodesic.parent[first_point[k]];
            parent[k] = up < 0 ? -1 : c.of_point[up];
        }
    return parent;
}

// Thickness of each cluster's slice: the square root of the middle eigenvalue of its
// covariance, r / sqrt(2) for a ring of radius r (and for an arc of it) whatever the bin width,
// which only shows in the largest (thin branch) or smallest (thick stem) eigenvalue.
std::vector<float> slice_thickness(std::span<const Eigen::Vector3f> points, const Clusters& c) {
    std::vector<Eigen::Matrix3d> second(c.size(), Eigen::Matrix3d::Zero());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector3d d = points[i].cast<double>() - c.centroid(c.of_point[i]);
        second[c.of_point[i]] += d * d.transpose();
    }
    std::vector<float> thickness(c.size());
    for (std::size_t k = 0; k < c.size(); ++k) {
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(second[k] / static_cast<double>(c.count[k]), Eigen::EigenvaluesOnly);
        thickness[k] = static_cast<float>(std::sqrt(std::max(0.0, solver.eigenvalues()[1])));
    }
    return thickness;
}

// The geodesic distance counted in bins: with one width everywhere, length / width; with a
// width per point, the path length from the base where each step counts in the width of the
// point it reaches (accumulated along the geodesic tree, parents first), so thin branches are cut
// into finer slices than thick stems. The width changes only from one slice to the next, so
// every level set stays a cross-section.
std::vector<float> bin_levels(const NeighbourGraph& graph, const ShortestPaths& sp, float width, const std::vector<float>& point_width,
                              int smoothing) {
    if (point_width.empty()) {
        std::vector<float> level = smoothed_lengths(graph, sp.length, smoothing);
        for (float& l : level) l /= width;
        return level;
    }
    std::vector<float> warped(sp.length.size(), 0.0f);
    for (int v : sp.order) {
        const int u = sp.parent[v];
        warped[v] = u < 0 ? sp.length[v] / point_width[v] : warped[u] + (sp.length[v] - sp.length[u]) / point_width[v];
    }
    return smoothed_lengths(graph, warped, smoothing);
}

// `point_width` (empty: `width` everywhere) gives each point its own bin width.
Clusters cluster_bins(std::span<const Eigen::Vector3f> points, const NeighbourGraph& graph, const KnnTable& near, const ShortestPaths& sp,
                      const ShortestPaths& weighted, float width, const std::vector<float>& point_width, float join, int smoothing) {
    const int n = static_cast<int>(points.size());
    const std::vector<float> level = bin_levels(graph, sp, width, point_width, smoothing);
    std::vector<int> bin(points.size());
    for (int i = 0; i < n; ++i) bin[i] = static_cast<int>(std::floor(level[i]));
    // Same-bin points belong together when they are at most `join` apart (scaled like the bin
    // width on thin branches), with or without a graph edge: on sparse bark a bin's band is only
    // two or three samples tall and its kNN edges leave gaps. Graph edges join same-bin points of
    // thick slices whatever their length (a sparse ring needs them), but not of thin ones: there
    // the longer edges (up to the gap length) would tie neighbouring twigs into one cluster whose
    // centroid floats between them.
    auto joined = [&](int i, int j, float d2) {
        if (bin[i] != bin[j]) return false;
        const float limit = point_width.empty() ? join : join * std::min(point_width[i], point_width[j]) / width;
        return d2 <= limit * limit;
    };
    auto thick_point = [&](int i) { return point_width.empty() || point_width[i] >= width; };
    UnionFind sets(points.size());
    for (int i = 0; i < n; ++i)
        for (std::uint32_t e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e) {
            const int j = graph.targets[e];
            if (j <= i || bin[i] != bin[j]) continue;
            if (thick_point(i) || thick_point(j) || joined(i, j, graph.lengths[e] * graph.lengths[e])) sets.unite(i, j);
        }
    for (int i = 0; i < n; ++i) {
        const int* row = near.row(i);
        const float* d2 = near.row_distances(i);
        for (int j = 0; j < near.k; ++j)
            if (row[j] >= 0 && joined(i, row[j], d2[j])) sets.unite(i, row[j]);
    }
    // Clusters are numbered in the order their first point was settled, so clusters of lower
    // bins mostly have smaller numbers.
    Clusters c;
    c.of_point.assign(points.size(), -1);
    std::vector<int> id_of_set(points.size(), -1), first_point;
    for (int u : sp.order) {
        const int set = sets.find(u);
        if (id_of_set[set] < 0) {
            id_of_set[set] = static_cast<int>(c.bin.size());
            first_point.push_back(u);
            c.bin.push_back(bin[u]);
            c.sum.emplace_back(Eigen::Vector3d::Zero());
            c.sum_sq.push_back(0.0);
            c.count.push_back(0);
        }
        const int id = id_of_set[set];
        c.of_point[u] = id;
        c.sum[id] += points[u].cast<double>();
        c.sum_sq[id] += points[u].cast<double>().squaredNorm();
        ++c.count[id];
    }
    c.parent = cluster_parents(c, first_point, sp, weighted);
    return c;
}

// True when some point of the clusters `a` is closer than `gap` to some point of the clusters
// `b`: arcs of one wide ring, split where the ring dips into the next bin, nearly touch.
bool gap_below(std::span<const Eigen::Vector3f> points, const std::vector<std::vector<int>>& points_of, const std::vector<int>& a,
               const std::vector<int>& b, double gap) {
    const float g2 = static_cast<float>(gap * gap);
    for (int ca : a)
        for (int i : points_of[ca])
            for (int cb : b)
                for (int j : points_of[cb])
                    if ((points[i] - points[j]).squaredNorm() < g2) return true;
    return false;
}

// Sibling clusters of one bin are pieces of one branch cross-section (sparse or one-sided
// scans) when their centroids are closer than `distance`, or closer than 0.9 times the sum of
// their spreads while both lie within the parent's footprint (twice its spread). Two arcs of
// one ring pass this test (centroid distance about 1.3 r against spreads of about 0.8 r each);
// two separate stems do not, however close. Arcs of a wide ring (one-sided or sparse scans of
// a thick stem) that nearly touch (a gap under a quarter of the footprint) merge as well.
// Merged siblings' children meet as siblings in the next bin and are merged in turn.
Clusters merge_fragments(std::span<const Eigen::Vector3f> points, const Clusters& in, float distance, float root_spread) {
    const int m = static_cast<int>(in.size());
    std::vector<std::vector<int>> points_of(m);
    for (std::size_t i = 0; i < in.of_point.size(); ++i) points_of[in.of_point[i]].push_back(static_cast<int>(i));
    std::vector<int> rep(m);
    std::iota(rep.begin(), rep.end(), 0);
    std::vector<std::vector<int>> members(m), children(m + 1);  // children[m]: hanging from the root
    for (int c = 0; c < m; ++c) {
        members[c] = {c};
        children[in.parent[c] < 0 ? m : in.parent[c]].push_back(c);
    }
    Clusters work = in;
    auto merge_into = [&](int keep, int gone) {
        for (int x : members[gone]) rep[x] = keep;
        members[keep].insert(members[keep].end(), members[gone].begin(), members[gone].end());
        members[gone].clear();
        work.sum[keep] += work.sum[gone];
        work.sum_sq[keep] += work.sum_sq[gone];
        work.count[keep] += work.count[gone];
    };
    for (int p = -1; p < m; ++p) {
        if (p >= 0 && rep[p] != p) continue;
        std::vector<int> kids;
        if (p < 0)
            kids = children[m];
        else
            for (int x : members[p]) kids.insert(kids.end(), children[x].begin(), children[x].end());
        std::sort(kids.begin(), kids.end());
        const double footprint = 2.0 * (p < 0 ? root_spread : work.spread(p));
        // Greedy in cluster order: each kid joins the first earlier kid of its bin close enough.
        for (std::size_t a = 0; a < kids.size(); ++a)
            for (std::size_t b = 0; b < a; ++b) {
                const int ka = kids[a], kb = kids[b];
                if (rep[kb] != kb || rep[ka] != ka || in.bin[ka] != in.bin[kb]) continue;
                const double d = (work.centroid(ka) - work.centroid(kb)).norm();
                const bool fragments = d < footprint && d < 0.9 * (work.spread(ka) + work.spread(kb));
                if (d < distance || fragments ||
                    (d < footprint && gap_below(points, points_of, members[ka], members[kb], 0.25 * footprint))) {
                    merge_into(kb, ka);
                    break;
                }
            }
    }
    Clusters out;
    std::vector<int> new_id(m, -1);
    for (int c = 0; c < m; ++c)
        if (rep[c] == c) {
            new_id[c] = static_cast<int>(out.parent.size());
            out.parent.push_back(in.parent[c] < 0 ? -1 : new_id[rep[in.parent[c]]]);
            out.bin.push_back(in.bin[c]);
            out.sum.push_back(work.sum[c]);
            out.sum_sq.push_back(work.sum_sq[c]);
            out.count.push_back(work.count[c]);
        }
    out.of_point.resize(in.of_point.size());
    for (std::size_t i = 0; i < in.of_point.size(); ++i) out.of_point[i] = new_id[rep[in.of_point[i]]];
    return out;
}

// Where the geodesic distance winds around a sparse thick stem (it runs along the bark as
// easily as up it), a bin is an arc of a helix rather than a cross-section, its centroid lies on
// the bark and the circle fit across the cluster's own direction fails or finds a small circle
// on the arc. The stem's cross-section is then cut directly: a slab one bin thick, across the
// axis that circle fits found below (the parent and up to four further ancestors, all on the
// axis), at the height of the cluster's centroid along that axis, holding the points of the
// clusters near it in the cluster tree (arcs of one height lie many bins apart along the
// winding). The circle fitted to the slab places the node when it is trustworthy and continues
// the stem (centre within half a radius of the extrapolated axis, radius within a factor 1.6
// of the stem's). A slab too sparse for a fit continues the axis below, for up to 16 bin widths
// of axis length (measured along the axis, not in clusters: the arcs of a winding stretch follow
// one another at nearly one height), when
// that axis is straight and the cluster's own points lie on the stem's ring (an arc of it, not
// a branch leaving it). Stems thinner than 0.12 m keep their clusters' own fits (tried down to
// 0.04 m: worse on archi and HS).
struct SlabFit {
    Eigen::Vector3f position;
    float radius = 0.0f;
    bool extrapolated = false;  // too sparse for a fit: on the axis below
    float rise = 0.0f;          // metres along the axis from the node below
};

std::optional<SlabFit> slab_centre(std::span<const Eigen::Vector3f> points, const Clusters& c, const std::vector<std::vector<int>>& members,
                                   const std::vector<std::vector<int>>& children, const std::vector<Eigen::Vector3f>& position,
                                   const std::vector<bool>& on_axis, float stem, float extrapolated, int k, float spacing,
                                   float bin_width) {
    constexpr std::size_t sparse_slab = 24;    // points a slab needs for a circle fit
    constexpr float max_extrapolated = 16.0f;  // bin widths of axis length
    constexpr float min_slab_radius = 0.12f;   // metres: thinner stems keep the clusters' own fits
    constexpr int reach = 8;                   // bins either side whose clusters the slab draws from
    if (!(stem >= std::max(2.0f * spacing, min_slab_radius))) return std::nullopt;
    const int below = c.parent[k];
    const Eigen::Vector3f base = position[below];
    // The axis below: on-axis ancestors back to four bin widths away (nodes of a winding stretch
    // may share one position), at least two.
    int low = below;
    for (int step = 0; step < 16 && c.parent[low] >= 0 && on_axis[c.parent[low]] && (base - position[low]).norm() < 4.0f * bin_width;
         ++step)
        low = c.parent[low];
    if ((base - position[low]).norm() < 2.0f * bin_width) return std::nullopt;
    const Eigen::Vector3f direction = (base - position[low]).normalized();
    const Eigen::Vector3f centroid = c.centroid(k).cast<float>();
    const float t = (centroid - base).dot(direction);
    if (!(t > -bin_width) || t > 2.0f * bin_width) return std::nullopt;
    // An arc winding level with the node below: the stem has not risen.
    const Eigen::Vector3f centre = base + std::max(t, 0.0f) * direction;
    if ((centroid - centre).norm() > 1.5f * stem) return std::nullopt;  // beside the stem
    const Eigen::Vector3f u = direction.unitOrthogonal(), v = direction.cross(u);
    auto across = [&](const Eigen::Vector3f& p) { return Eigen::Vector2f((p - centre).dot(u), (p - centre).dot(v)); };
    // The cluster's own points must lie on the ring of radius r around `axis` (in the plane).
    auto on_ring = [&](const Eigen::Vector2f& axis, float r) {
        const float band = std::max(2.0f * spacing, 0.4f * r);
        std::size_t near = 0;
        for (int i : members[k]) near += std::abs((across(points[i]) - axis).norm() - r) < band;
        return 10 * near >= 7 * members[k].size();
    };
    int top = k;
    while (c.parent[top] >= 0 && c.bin[c.parent[top]] >= c.bin[k] - reach) top = c.parent[top];
    std::vector<Eigen::Vector2f> flat;
    std::vector<int> stack{top};
    while (!stack.empty()) {
        const int x = stack.back();
        stack.pop_back();
        for (int i : members[x])
            if (std::abs((points[i] - centre).dot(direction)) <= 0.5f * bin_width && across(points[i]).norm() <= 3.0f * stem)
                flat.push_back(across(points[i]));
        for (int y : children[x])
            if (c.bin[y] <= c.bin[k] + reach) stack.push_back(y);
    }
    if (flat.size() < sparse_slab) {
        if (extrapolated + std::max(t, 0.0f) > max_extrapolated * bin_width || !on_ring(Eigen::Vector2f::Zero(), stem)) return std::nullopt;
        // Only a straight axis is continued (a curving limb would soon leave it): the axis below
        // must bend by less than 20 degrees between its lower and upper halves.
        const float half = 0.5f * (base - position[low]).norm();
        int mid = below;
        while (mid != low && (base - position[mid]).norm() < half) mid = c.parent[mid];
        if (mid == low || (position[mid] - position[low]).norm() < 0.25f * half) return std::nullopt;
        const Eigen::Vector3f lower = (position[mid] - position[low]).normalized(), upper = (base - position[mid]).normalized();
        if (lower.dot(upper) < std::cos(20.0f * std::numbers::pi_v<float> / 180.0f)) return std::nullopt;
        return SlabFit{centre, stem, true, std::max(t, 0.0f)};
    }
    const CircleFit circle = fit_circle(flat, std::max(0.005f, spacing), stem / 1.6f, 1.6f * stem, 100);
    const bool trusted = circle.ok && circle.coverage >= 0.2f && circle.inliers * 2 >= flat.size() && circle.rms < 0.25f * circle.radius &&
                         circle.centre.norm() < 0.5f * circle.radius;
    if (!trusted) return std::nullopt;
    return SlabFit{centre + circle.centre.x() * u + circle.centre.y() * v, circle.radius, false};
}

// Where a cluster sits on its branch axis. The centroid of a thick branch's slice lies on the
// scanned side of the bark, not on the axis (a half-visible stem puts it 0.64 r off), so for
// wide clusters a circle is fitted across the local branch direction and its centre used
// when the fit is trustworthy (enough of the circle seen, small residuals). `fitted` receives,
// per cluster, whether a trusted circle or slab fit placed it.
std::vector<Eigen::Vector3f> axis_positions(std::span<const Eigen::Vector3f> points, const Clusters& c, float spacing, float bin_width,
                                            bool fit, std::vector<char>& fitted) {
    std::vector<Eigen::Vector3f> position(c.size());
    for (std::size_t k = 0; k < c.size(); ++k) position[k] = c.centroid(static_cast<int>(k)).cast<float>();
    fitted.assign(c.size(), 0);
    if (!fit) return position;
    std::vector<std::vector<int>> members(c.size()), children(c.size());
    for (std::size_t i = 0; i < points.size(); ++i) members[c.of_point[i]].push_back(static_cast<int>(i));
    for (std::size_t k = 0; k < c.size(); ++k)
        if (c.parent[k] >= 0) children[c.parent[k]].push_back(static_cast<int>(k));
    std::vector<Eigen::Vector2f> flat;
    std::size_t tried = 0, moved = 0, inherited = 0;
    // Offset from the centroid to the fitted axis; a thick slice whose own fit is not trusted
    // takes its parent's (a one-sided scan is one-sided all along the stem).
    std::vector<Eigen::Vector3f> offset(c.size(), Eigen::Vector3f::Zero());
    std::vector<bool> has_offset(c.size(), false);
    std::vector<bool> on_axis(c.size(), false);       // placed by a trusted circle or slab fit
    std::vector<float> axis_radius(c.size(), 0.0f);   // of that circle
    std::vector<float> extrapolated(c.size(), 0.0f);  // axis length over consecutive slabs too sparse to fit, up to this cluster
    std::size_t resliced = 0;
    for (std::size_t k = 0; k < c.size(); ++k) {
        // A window of three bins (parent, cluster, only child) gives the fit more of the bark.
        const int below = c.parent[k];
        const int above = children[k].size() == 1 ? children[k].front() : -1;
        // A cluster on a thick stem whose axis is known below is placed by a slab across that
        // axis (its own bin may be an arc of a winding geodesic); elsewhere by its own fit.
        if (below >= 0 && on_axis[below]) {
            if (const auto slab = slab_centre(points, c, members, children, position, on_axis, axis_radius[below], extrapolated[below],
                                              static_cast<int>(k), spacing, bin_width)) {
                ++resliced;
                extrapolated[k] = slab->extrapolated ? extrapolated[below] + slab->rise : 0.0f;
                position[k] = slab->position;
                axis_radius[k] = slab->radius;
                on_axis[k] = true;
                continue;
            }
        }
        // The branch direction over up to three clusters either side: slice centroids of a
        // one-sided scan zigzag, and a tilted projection plane smears the circle. Positions
        // below are final already (parents come first). At a branch end or a fork the last
        // slice is often a partial arc: the direction then comes from the nodes below.
        int low = static_cast<int>(k), high = static_cast<int>(k);
        for (int step = 0; step < 3; ++step) {
            if (c.parent[low] >= 0) low = c.parent[low];
            if (children[high].size() == 1) high = children[high].front();
        }
        const Eigen::Vector3f from = position[low];
        const Eigen::Vector3f to = high != static_cast<int>(k)    ? c.centroid(high).cast<float>()
                                   : (below >= 0 && low != below) ? position[below]
                                                                  : position[k];
        if ((to - from).norm() < 1e-6f) continue;
        const Eigen::Vector3f direction = (to - from).normalized();
        const Eigen::Vector3f u = direction.unitOrthogonal(), v = direction.cross(u);
        flat.clear();
        double spread = 0;
        for (int window : {below, static_cast<int>(k), above}) {
            if (window < 0) continue;
            for (int i : members[window]) {
                const Eigen::Vector3f d = points[i] - position[k];
                flat.emplace_back(d.dot(u), d.dot(v));
                spread += flat.back().squaredNorm();
            }
        }
        if (flat.size() < 12) continue;
        spread = std::sqrt(spread / static_cast<double>(flat.size()));
        if (spread < std::max(2.0 * spacing, 0.04)) continue;  // thin branch: the centroid is near the axis already
        ++tried;
        const CircleFit circle =
                fit_circle(flat, std::max(0.005f, spacing), 0.5f * static_cast<float>(spread), 4.0f * static_cast<float>(spread), 100);
        const bool trusted = circle.ok && circle.coverage >= 0.2f && circle.inliers * 2 >= flat.size() &&
                             circle.rms < 0.25f * circle.radius && circle.centre.norm() < circle.radius;
        if (!trusted) {
            const double parent_spread = below >= 0 ? c.spread(below) : 0.0;
            // Only along an unbranched stretch of similar thickness, and only a clearly
            // one-sided offset (a full ring's offset is fit noise, not worth passing on).
            if (below >= 0 && has_offset[below] && children[below].size() == 1 &&
                std::abs(c.spread(static_cast<int>(k)) - parent_spread) < 0.3 * parent_spread &&
                offset[below].norm() > 0.5 * parent_spread) {
                offset[k] = offset[below];
                has_offset[k] = true;
                position[k] += offset[k];
                ++inherited;
            }
            continue;
        }
        ++moved;
        offset[k] = circle.centre.x() * u + circle.centre.y() * v;
        has_offset[k] = true;
        on_axis[k] = true;
        axis_radius[k] = circle.radius;
        position[k] += offset[k];
    }
    log_debug("skeleton: circle fits tried on " + std::to_string(tried) + " of " + std::to_string(c.size()) + " clusters, " +
              std::to_string(moved) + " moved onto the fitted axis, " + std::to_string(resliced) +
              " onto a slab fit across the axis below, " + std::to_string(inherited) + " took their parent's offset");
    for (std::size_t k = 0; k < c.size(); ++k) fitted[k] = on_axis[k];
    return position;
}

// Clusters reached from the base only across a gap longer than `max_gap` (an edge of the
// geodesic shortest-path tree), and everything above them. Such pieces hang on a guessed
// connection; the lobe stage rather than the skeleton should represent them. With
// `max_points` > 0 only small pieces go: a piece is everything the shortest-path tree reaches
// through the gap edge, and one of `max_points` points or more stays, since a big branch seen
// across a gap is worth its straight join. A cluster goes when all its points are in pieces
// that go (or its parent goes).
std::vector<bool> detached_clusters(const Clusters& c, const NeighbourGraph& graph, const ShortestPaths& sp, float max_gap,
                                    int max_points) {
    std::vector<bool> detached(c.size(), false);
    if (!(max_gap > 0)) return detached;
    const std::size_t n = sp.parent.size();
    std::vector<float> hop(n, 0.0f);  // length of the edge from a point's parent
    for (int v : sp.order) {
        const int u = sp.parent[v];
        if (u < 0) continue;
        for (std::uint32_t e = graph.offsets[v]; e < graph.offsets[v + 1]; ++e)
            if (graph.targets[e] == u) hop[v] = graph.lengths[e];
    }
    std::vector<int> above(n, 1);                                   // points of the shortest-path subtree from each point up
    for (auto it = sp.order.rbegin(); it != sp.order.rend(); ++it)  // children before parents
        if (sp.parent[*it] >= 0) above[sp.parent[*it]] += above[*it];
    std::vector<char> gone(n, 0);
    for (int v : sp.order) {  // parents first
        const int u = sp.parent[v];
        gone[v] = (u >= 0 && gone[u]) || (hop[v] > max_gap && (max_points <= 0 || above[v] < max_points));
    }
    std::vector<char> all_gone(c.size(), 1);
    for (std::size_t i = 0; i < n; ++i)
        if (!gone[i]) all_gone[c.of_point[i]] = 0;
    for (std::size_t k = 0; k < c.size(); ++k)  // parents come first
        detached[k] = all_gone[k] || (c.parent[k] >= 0 && detached[c.parent[k]]);
    return detached;
}

// Node 0 at the stem foot, node c+1 at the axis position of cluster c. Until allometry sets
// the radii, a node's radius holds its cluster's spread (a measured thickness) for pruning.
TreeGraph cluster_tree(const Clusters& c, const std::vector<Eigen::Vector3f>& position, const Eigen::Vector3f& root, float root_spread) {
    TreeGraph tree;
    tree.add_node(root, root_spread, -1);
    for (std::size_t k = 0; k < c.size(); ++k)
        tree.add_node(position[k], static_cast<float>(c.spread(static_cast<int>(k))), c.parent[k] + 1);
    return tree;
}

std::vector<float> chain_lengths(const TreeGraph& tree, const std::vector<std::vector<int>>& chains) {
    std::vector<float> lengths;
    for (const auto& chain : chains) {
        float l = 0;
        for (std::size_t i = 1; i < chain.size(); ++i) l += tree.edge_length(chain[i]);
        lengths.push_back(l);
    }
    return lengths;
}

// Distance from p to the polyline through `nodes`.
float distance_to_polyline(const TreeGraph& tree, const std::vector<int>& nodes, const Eigen::Vector3f& p) {
    float best = std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const Eigen::Vector3f a = tree.nodes[nodes[i]].position;
        if (i + 1 == nodes.size()) {
            best = std::min(best, (p - a).norm());
            break;
        }
        const Eigen::Vector3f ab = tree.nodes[nodes[i + 1]].position - a;
        const float t = ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0f, 1.0f) : 0.0f;
        best = std::min(best, (a + t * ab - p).norm());
    }
    return best;
}

// Per-node flags carried through keep_nodes: a kept node keeps its flag under its new number.
std::vector<char> kept_flags(const std::vector<char>& flags, const std::vector<bool>& keep, const std::vector<int>& new_index,
                             std::size_t size) {
    std::vector<char> out(size, 0);
    for (std::size_t u = 0; u < flags.size(); ++u)
        if (keep[u]) out[static_cast<std::size_t>(new_index[u])] = flags[u];
    return out;
}

// Removes spurious leaf chains hanging from a fork: those whose tip stays closer than
// `min_length` (or than twice the thickness of the fork: bark bumps and scan fragments of a
// thick stem) to the axis the fork belongs to (the node below the fork and the fork's longest
// chain). Never every branch of a fork: the chain holding the most points survives (at a
// ragged branch end, a longer chain may be a few points of bark). Repeats until nothing
// changes. Updates node_of_point and the per-node flags.
std::size_t prune_twigs(TreeGraph& tree, float min_length, std::vector<int>& node_of_point, std::vector<char>& flags) {
    std::size_t removed = 0;
    for (int round = 0; round < 20; ++round) {
        const auto chains = tree_chains(tree);
        const auto lengths = chain_lengths(tree, chains);
        std::vector<std::size_t> points_of_node(tree.size(), 0);
        for (int node : node_of_point) ++points_of_node[node];
        std::vector<std::size_t> weight(chains.size(), 0);
        for (std::size_t k = 0; k < chains.size(); ++k)
            for (std::size_t i = 1; i < chains[k].size(); ++i) weight[k] += points_of_node[chains[k][i]];
        std::map<int, std::vector<std::size_t>> by_fork;  // fork -> its chains
        for (std::size_t k = 0; k < chains.size(); ++k) by_fork[chains[k].front()].push_back(k);
        std::vector<bool> keep(tree.size(), true);
        bool changed = false;
        for (const auto& [fork, list] : by_fork) {
            if (list.size() < 2) continue;
            std::size_t longest = list.front();  // the fork's main chain
            for (std::size_t k : list)
                if (weight[k] > weight[longest]) longest = k;
            std::vector<int> axis = chains[longest];
            if (tree.nodes[fork].parent >= 0) axis.insert(axis.begin(), tree.nodes[fork].parent);
            const float limit = std::max(min_length, 2.0f * tree.nodes[fork].radius);
            for (std::size_t k : list) {
                const bool leaf = tree.nodes[chains[k].back()].children.empty();
                if (k == longest || !leaf) continue;
                const float reach = std::min(lengths[k], distance_to_polyline(tree, axis, tree.nodes[chains[k].back()].position));
                if (reach >= limit) continue;
                for (std::size_t i = 1; i < chains[k].size(); ++i) keep[chains[k][i]] = false;
                removed += chains[k].size() - 1;
                changed = true;
            }
        }
        if (!changed) break;
        std::vector<int> new_index;
        tree = keep_nodes(tree, keep, new_index);
        for (int& node : node_of_point) node = new_index[node];
        flags = kept_flags(flags, keep, new_index, tree.size());
    }
    return removed;
}

// Laplacian smoothing of chain interiors; forks, tips and the root stay where they are.
void smooth_chains(TreeGraph& tree, int iterations) {
    const auto chains = tree_chains(tree);
    for (int it = 0; it < iterations; ++it)
        for (const auto& chain : chains) {
            if (chain.size() < 3) continue;
            std::vector<Eigen::Vector3f> p;
            for (int node : chain) p.push_back(tree.nodes[node].position);
            for (std::size_t i = 1; i + 1 < chain.size(); ++i)
                tree.nodes[chain[i]].position = 0.25f * p[i - 1] + 0.5f * p[i] + 0.25f * p[i + 1];
        }
}

// Position at arc length `s` along a polyline with cumulative lengths `arc`.
Eigen::Vector3f point_at(const std::vector<Eigen::Vector3f>& p, const std::vector<float>& arc, float s) {
    const auto it = std::upper_bound(arc.begin(), arc.end(), s);
    const std::size_t i = std::clamp<std::size_t>(static_cast<std::size_t>(it - arc.begin()), 1, p.size() - 1);
    const float span = arc[i] - arc[i - 1];
    const float t = span > 0 ? std::clamp((s - arc[i - 1]) / span, 0.0f, 1.0f) : 1.0f;
    return p[i - 1] + t * (p[i] - p[i - 1]);
}

// Resamples every chain to round(L / l) internodes of equal length; forks and tips stay
// exact. new_of_old[old node] = new node at the upper end of the internode covering it. A new
// node is flagged (new_flags) when both old nodes of the stretch it lies on are (flags).
TreeGraph resample(const TreeGraph& tree, float l, std::vector<int>& new_of_old, const std::vector<char>& flags,
                   std::vector<char>& new_flags) {
    TreeGraph out;
    out.origin = tree.origin;
    out.add_node(tree.nodes[0].position, 0.0f, -1);
    new_flags.assign(1, flags[0]);
    new_of_old.assign(tree.size(), -1);
    new_of_old[0] = 0;
    for (const auto& chain : tree_chains(tree)) {
        std::vector<Eigen::Vector3f> p;
        std::vector<float> arc{0.0f};
        for (std::size_t i = 0; i < chain.size(); ++i) {
            p.push_back(tree.nodes[chain[i]].position);
            if (i > 0) arc.push_back(arc.back() + (p[i] - p[i - 1]).norm());
        }
        const float total = arc.back();
        int previous = new_of_old[chain.front()];
        if (total < 1e-6f) {  // coincident nodes: nothing to add
            for (std::size_t i = 1; i < chain.size(); ++i) new_of_old[chain[i]] = previous;
            continue;
        }
        const int m = std::max(1, static_cast<int>(std::lround(total / l)));
        const float step = total / static_cast<float>(m);
        std::vector<int> created(static_cast<std::size_t>(m) + 1, previous);
        for (int t = 1; t <= m; ++t) {
            const float s = step * static_cast<float>(t);
            const Eigen::Vector3f pos = t == m ? p.back() : point_at(p, arc, s);
            previous = out.add_node(pos, 0.0f, previous);
            created[t] = previous;
            const std::size_t i =
                    t == m ? chain.size() - 1
                           : std::clamp<std::size_t>(static_cast<std::size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin()), 1,
                                                     chain.size() - 1);
            new_flags.push_back(flags[chain[i - 1]] && flags[chain[i]]);
        }
        for (std::size_t i = 1; i < chain.size(); ++i) {
            const int t = std::clamp(static_cast<int>(std::ceil(arc[i] / step - 1e-4f)), 1, m);
            new_of_old[chain[i]] = created[t];
        }
    }
    return out;
}

void check_points(std::span<const Eigen::Vector3f> points, const std::string& name) {
    if (points.size() < 10) throw Error::input(name, "too few points for a skeleton (" + std::to_string(points.size()) + ")");
    for (const auto& p : points)
        if (!p.allFinite()) throw Error::input(name, "a point has a non-finite coordinate");
}

// The geodesic slicing: the tree's points, their graph and both shortest-path runs.
struct Slicing {
    std::span<const Eigen::Vector3f> points;
    const NeighbourGraph& graph;
    const KnnTable& near;
    const ShortestPaths& sp;
    const ShortestPaths& weighted;
    float bin_width, merge, root_spread;
    int geodesic_smoothing;

    Clusters clusters(const std::vector<float>& point_width) const {
        return merge_fragments(points,
                               cluster_bins(points, graph, near, sp, weighted, bin_width, point_width, bin_width, geodesic_smoothing),
                               merge, root_spread);
    }
};

// Bin width of every point. A first slicing at the full width measures how thick the branch is
// around every point; thin branches are then sliced again at a finer width (their axis bends
// within a wide bin, and nearby twigs share one), thick stems keep the wide bins that hold their
// rings together. Empty: every point at the full width.
std::vector<float> point_bin_widths(const Slicing& slicing, const SkeletonOptions& o) {
    std::vector<float> point_width;
    if (!(o.fine_bin_factor < 1.0f)) return point_width;
    const float full = slicing.bin_width;
    const float fine = o.fine_bin_factor * full;
    const Clusters coarse = slicing.clusters({});
    const std::vector<float> thickness = slice_thickness(slicing.points, coarse);
    point_width.resize(slicing.points.size());
    const float thick = o.thick_slice * full;
    // A slice counts as thin only above two thin slices: a ring cut at two widths falls
    // apart, so the first slices of a branch leaving a thick stem keep the stem's width, and
    // so do crumbs at the ragged edge of a one-sided ring.
    auto thin = [&](int k) { return k >= 0 && thickness[k] < thick; };
    for (std::size_t i = 0; i < slicing.points.size(); ++i) {
        const int k = coarse.of_point[i], up = coarse.parent[k];
        point_width[i] = thin(k) && thin(up) && thin(coarse.parent[up]) ? fine : full;
    }
    log_debug("skeleton: " + std::to_string(std::count(point_width.begin(), point_width.end(), full)) + " of " +
              std::to_string(slicing.points.size()) + " points on thick slices (full bin width)");
    return point_width;
}

// Clusters beyond gaps (max_gap, max_gap_points) leave the skeleton; returns the points they held.
std::size_t leave_out_detached(const Clusters& clusters, const NeighbourGraph& graph, const ShortestPaths& sp, const SkeletonOptions& o,
                               TreeGraph& tree, std::vector<int>& node_of_point, std::vector<char>& on_axis) {
    const std::vector<bool> detached = detached_clusters(clusters, graph, sp, o.max_gap, o.max_gap_points);
    if (std::find(detached.begin(), detached.end(), true) == detached.end()) return 0;
    std::vector<bool> keep(tree.size(), true);
    for (std::size_t k = 0; k < detached.size(); ++k) keep[k + 1] = !detached[k];
    std::size_t detached_points = 0;
    for (std::size_t i = 0; i < node_of_point.size(); ++i) detached_points += detached[clusters.of_point[i]];
    log_debug("skeleton: " + std::to_string(detached_points) + " points in " +
              std::to_string(std::count(detached.begin(), detached.end(), true)) + " clusters beyond gaps left out of the skeleton");
    std::vector<int> new_index;
    tree = keep_nodes(tree, keep, new_index);
    for (int& node : node_of_point) node = new_index[node];
    on_axis = kept_flags(on_axis, keep, new_index, tree.size());
    return detached_points;
}

// Internodes of equal length, children ordered by subtree length, nodes renumbered; the root's
// points go to the first internode above it (the root has no internode of its own).
void resample_internodes(TreeGraph& tree, float internode_length, std::vector<int>& node_of_point, std::vector<char>& on_axis) {
    for (auto& node : tree.nodes) node.radius = 0.0f;  // spreads served their purpose
    std::vector<int> map;
    std::vector<char> resampled_on_axis;
    tree = resample(tree, internode_length, map, on_axis, resampled_on_axis);
    for (int& node : node_of_point) node = map[node];
    tree.order_children_by_subtree_length();
    const std::vector<bool> all(tree.size(), true);
    tree = keep_nodes(tree, all, map);
    for (int& node : node_of_point) node = map[node];
    on_axis = kept_flags(resampled_on_axis, all, map, tree.size());
    const int first = tree.nodes[0].children.empty() ? 0 : tree.nodes[0].children.front();
    for (int& node : node_of_point)
        if (node == 0) node = first;
}

}  // namespace

SkeletonResult reconstruct_skeleton(std::span<const Eigen::Vector3f> points, const SkeletonOptions& o, const std::string& name,
                                    const KdTree* given_index, const KnnTable* given_near) {
    check_options(o);
    check_points(points, name);

    SkeletonResult r;
    auto clock = std::chrono::steady_clock::now();
    auto lap = [&clock](const char* what) {  // stage timings for --log-level debug
        const auto now = std::chrono::steady_clock::now();
        log_debug(std::string("skeleton: ") + what + " " + std::to_string(std::chrono::duration<double>(now - clock).count()) + " s");
        clock = now;
    };
    std::optional<KdTree> own_index;
    if (!given_index || given_index->size() != points.size()) given_index = &own_index.emplace(points);
    const KdTree& index = *given_index;
    const int width = skeleton_table_width(o);
    KnnTable own_near;
    if (!given_near || given_near->k != width || given_near->indices.size() != points.size() * static_cast<std::size_t>(width)) {
        own_near = knn_of_all_points(index, width);
        given_near = &own_near;
    }
    const KnnTable& near = *given_near;
    NeighbourGraphOptions graph_options{o.neighbours, o.beta, o.max_edge_length, true};
    graph_options.direction_weight = o.bridge_direction;
    const NeighbourGraph graph = build_neighbour_graph(points, graph_options, &index, &near);
    r.graph_components = graph.components;
    r.bridges = graph.bridges;
    r.longest_bridge = graph.longest_bridge;
    lap("neighbour graph");
    r.spacing = median_nearest_distance(graph);
    const float sampling = sampling_distance(near);
    r.bin_width = o.bin_width > 0 ? o.bin_width : std::clamp(2.5f * sampling, 0.02f, 0.5f);
    log_debug("skeleton: nearest-neighbour spacing " + std::to_string(r.spacing) + " m, sampling distance " + std::to_string(sampling) +
              " m");
    r.internode_length = o.internode_length > 0 ? o.internode_length : r.bin_width;
    const float twig = o.min_twig_length > 0 ? o.min_twig_length : 2.0f * r.bin_width;
    const float merge = o.merge_distance > 0 ? o.merge_distance : r.bin_width;

    r.base = find_tree_base(points, graph, o.base);
    // The weighted tree and the geodesic distances are independent runs: one per core.
    ShortestPaths weighted, sp;
    treelobes::parallel_invoke([&] { weighted = shortest_paths(graph, r.base.sources); },
                               [&] { sp = shortest_paths(graph, r.base.sources, EdgeCost::Length); });
    lap("base and shortest paths");
    const float root_spread = r.base.circle_fitted ? r.base.foot_radius : 0.0f;
    const Slicing slicing{points, graph, near, sp, weighted, r.bin_width, merge, root_spread, o.geodesic_smoothing};
    const Clusters clusters = slicing.clusters(point_bin_widths(slicing, o));
    r.clusters = clusters.size();
    lap("bins");

    std::vector<char> fitted;
    TreeGraph tree = cluster_tree(clusters, axis_positions(points, clusters, r.spacing, r.bin_width, o.fit_axes, fitted), r.base.position,
                                  root_spread);
    // Node flags: placed on a measured axis (the root by the foot's circle fit).
    std::vector<char> on_axis(tree.size(), 0);
    on_axis[0] = r.base.circle_fitted;
    for (std::size_t k = 0; k < fitted.size(); ++k) on_axis[k + 1] = fitted[k];
    lap("axis fits");
    std::vector<int> node_of_point(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) node_of_point[i] = clusters.of_point[i] + 1;
    r.detached_points = leave_out_detached(clusters, graph, sp, o, tree, node_of_point, on_axis);
    r.pruned_nodes = prune_twigs(tree, twig, node_of_point, on_axis);
    smooth_chains(tree, o.smoothing_iterations);

    resample_internodes(tree, r.internode_length, node_of_point, on_axis);
    lap("prune, smooth, resample");
    r.tree = std::move(tree);
    r.point_internode = std::move(node_of_point);
    r.point_geodesic = sp.length;
    r.node_on_axis.assign(on_axis.begin(), on_axis.end());
    return r;
}

TreeGraph extract_skeleton(const PointCloud& cloud, const SkeletonOptions& options) {
    SkeletonResult r = reconstruct_skeleton(cloud.positions, options);
    r.tree.origin = cloud.origin;
    return r.tree;
}

}  // namespace treelobes
