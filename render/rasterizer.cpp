#include "render/rasterizer.hpp"

#include "core/error.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace treelobes::render {

Rgba shade(Rgba colour, double light) {
    light = std::clamp(light, 0.0, 1.0);
    return {static_cast<std::uint8_t>(colour[0] * light), static_cast<std::uint8_t>(colour[1] * light),
            static_cast<std::uint8_t>(colour[2] * light), colour[3]};
}

View View::side(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double azimuth_deg, double elevation_deg) {
    const double az = azimuth_deg * M_PI / 180.0, el = elevation_deg * M_PI / 180.0;
    View view;
    view.forward = Eigen::Vector3d(std::sin(az) * std::cos(el), std::cos(az) * std::cos(el), -std::sin(el));
    view.up = Eigen::Vector3d(0, 0, 1);
    view.lo = lo;
    view.hi = hi;
    return view;
}

namespace {

struct ImageAxes {
    Eigen::Vector3d forward, right, up;
    double half_width = 1e-9, half_height = 1e-9;  // of the view's box on the image axes
};

ImageAxes image_axes(const View& view) {
    if (!view.forward.allFinite() || view.forward.norm() == 0) throw Error::usage("render: view direction is zero");
    ImageAxes axes;
    axes.forward = view.forward.normalized();
    // Image axes: right = forward x up, up = right x forward (Gram-Schmidt against forward).
    Eigen::Vector3d up = view.up - view.up.dot(axes.forward) * axes.forward;
    if (up.norm() < 1e-9) up = Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitY().dot(axes.forward) * axes.forward;
    axes.up = up.normalized();
    axes.right = axes.forward.cross(axes.up).normalized();
    const Eigen::Vector3d centre = 0.5 * (view.lo + view.hi);
    for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d p((corner & 1) ? view.hi.x() : view.lo.x(), (corner & 2) ? view.hi.y() : view.lo.y(),
                                (corner & 4) ? view.hi.z() : view.lo.z());
        axes.half_width = std::max(axes.half_width, std::abs((p - centre).dot(axes.right)));
        axes.half_height = std::max(axes.half_height, std::abs((p - centre).dot(axes.up)));
    }
    if (view.half_width > 0 && view.half_height > 0) {
        axes.half_width = view.half_width;
        axes.half_height = view.half_height;
    }
    return axes;
}

}  // namespace

double View::aspect() const {
    const ImageAxes axes = image_axes(*this);
    return axes.half_width / axes.half_height;
}

Rasterizer::Rasterizer(int width, int height, const View& view, Rgba background)
        : image_(width, height, background), depth_(static_cast<std::size_t>(width) * height, std::numeric_limits<double>::infinity()) {
    const ImageAxes axes = image_axes(view);
    forward_ = axes.forward;
    up_ = axes.up;
    right_ = axes.right;
    centre_ = 0.5 * (view.lo + view.hi);
    // Extent of the box's corners on the image axes decides the scale.
    const double usable = 1.0 - 2.0 * view.margin;
    scale_ = std::min(width * usable / (2 * axes.half_width), height * usable / (2 * axes.half_height));
}

Eigen::Vector3d Rasterizer::project(const Eigen::Vector3d& world) const {
    const Eigen::Vector3d d = world - centre_;
    return {image_.width / 2.0 + d.dot(right_) * scale_, image_.height / 2.0 - d.dot(up_) * scale_, d.dot(forward_)};
}

void Rasterizer::plot(int x, int y, double depth, Rgba colour) {
    if (x < 0 || y < 0 || x >= image_.width || y >= image_.height) return;
    double& z = depth_[static_cast<std::size_t>(y) * image_.width + x];
    if (depth >= z) return;
    z = depth;
    image_.set(x, y, colour);
}

void Rasterizer::fill_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, Rgba colour) {
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) return;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(image_.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(image_.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            const double px = x + 0.5, py = y + 0.5;
            // Barycentric weights; the sign of `area` handles both windings (two-sided).
            const double w0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
            const double w1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
            const double w2 = 1.0 - w0 - w1;
            if (w0 < 0 || w1 < 0 || w2 < 0) continue;
            plot(x, y, w0 * a.z() + w1 * b.z() + w2 * c.z(), colour);
        }
}

void Rasterizer::draw_mesh(const TriangleMesh& mesh, Rgba colour) {
    // Headlight from the viewer plus a little from above, two-sided Lambert.
    const Eigen::Vector3d light = (-forward_ + 0.5 * up_).normalized();
    for (const auto& f : mesh.faces) {
        Eigen::Vector3d world[3];
        for (int k = 0; k < 3; ++k) world[k] = mesh.origin + mesh.vertices[f[k]].cast<double>();
        const Eigen::Vector3d normal = (world[1] - world[0]).cross(world[2] - world[0]);
        if (normal.norm() == 0 || !normal.allFinite()) continue;
        const double lambert = std::abs(normal.normalized().dot(light));
        fill_triangle(project(world[0]), project(world[1]), project(world[2]), shade(colour, 0.35 + 0.65 * lambert));
    }
}

void Rasterizer::draw_points(const std::vector<Eigen::Vector3d>& points, const std::vector<Rgba>& colours, int size_px) {
    const int half = std::max(0, size_px - 1) / 2;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector3d p = project(points[i]);
        const Rgba colour = colours.size() == points.size() ? colours[i] : colours.front();
        for (int dy = -half; dy <= half; ++dy)
            for (int dx = -half; dx <= half; ++dx)
                plot(static_cast<int>(std::floor(p.x())) + dx, static_cast<int>(std::floor(p.y())) + dy, p.z(), colour);
    }
}

void Rasterizer::draw_points(const PointCloud& cloud, Rgba colour, int size_px) {
    std::vector<Eigen::Vector3d> points;
    points.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) points.push_back(cloud.global(i));
    // Shade by depth so that a dense scan still shows its shape.
    double near = std::numeric_limits<double>::max(), far = -near;
    for (const auto& p : points) {
        near = std::min(near, (p - centre_).dot(forward_));
        far = std::max(far, (p - centre_).dot(forward_));
    }
    std::vector<Rgba> colours;
    colours.reserve(points.size());
    for (const auto& p : points) {
        const double t = far > near ? ((p - centre_).dot(forward_) - near) / (far - near) : 0.0;
        colours.push_back(shade(colour, 1.0 - 0.6 * t));
    }
    if (!points.empty()) draw_points(points, colours, size_px);
}

void Rasterizer::draw_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Rgba colour) {
    const Eigen::Vector3d pa = project(a), pb = project(b);
    const int steps = std::max(1, static_cast<int>(std::ceil(std::max(std::abs(pb.x() - pa.x()), std::abs(pb.y() - pa.y())))));
    for (int i = 0; i <= steps; ++i) {
        const Eigen::Vector3d p = pa + (pb - pa) * (static_cast<double>(i) / steps);
        plot(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())), p.z() - 1e-6, colour);
    }
}

void Rasterizer::draw_skeleton(const TreeGraph& tree, Rgba colour) {
    for (std::size_t i = 1; i < tree.size(); ++i) {
        const auto& node = tree.nodes[i];
        draw_segment(tree.origin + tree.nodes[node.parent].position.cast<double>(), tree.origin + node.position.cast<double>(), colour);
    }
}

std::size_t Rasterizer::covered_pixels() const {
    return static_cast<std::size_t>(std::count_if(depth_.begin(), depth_.end(), [](double z) { return std::isfinite(z); }));
}

std::vector<bool> Rasterizer::coverage() const {
    std::vector<bool> mask(depth_.size());
    for (std::size_t i = 0; i < depth_.size(); ++i) mask[i] = std::isfinite(depth_[i]);
    return mask;
}

double silhouette_iou(const std::vector<bool>& a, const std::vector<bool>& b) {
    if (a.size() != b.size()) throw Error(ExitCode::Internal, "silhouette_iou: masks of different sizes");
    std::size_t both = 0, either = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        both += a[i] && b[i];
        either += a[i] || b[i];
    }
    return either == 0 ? 1.0 : static_cast<double>(both) / static_cast<double>(either);
}

namespace {

constexpr double kFar = 1e20;  // "no such pixel" in the squared distance transform

// One row or column of the squared Euclidean distance transform: d[q] = min over p of
// (q - p)^2 + f[p], by the lower envelope of parabolas (Felzenszwalb & Huttenlocher 2012).
void distance_1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v, std::vector<double>& z) {
    const int n = static_cast<int>(f.size());
    int k = 0;
    v[0] = 0;
    z[0] = -kFar;
    z[1] = kFar;
    const auto intersection = [&](int q, int p) {
        return ((f[q] + static_cast<double>(q) * q) - (f[p] + static_cast<double>(p) * p)) / (2.0 * (q - p));
    };
    for (int q = 1; q < n; ++q) {
        // z[0] = -kFar lies below every intersection (|f| <= kFar, q - p >= 1): k stays >= 0.
        double s = intersection(q, v[k]);
        while (s <= z[k]) s = intersection(q, v[--k]);
        ++k;
        v[k] = q;
        z[k] = s;
        z[k + 1] = kFar;
    }
    k = 0;
    for (int q = 0; q < n; ++q) {
        while (z[k + 1] < q) ++k;
        const double dq = q - v[k];
        d[q] = dq * dq + f[v[k]];
    }
}

// Squared distance of every pixel to the nearest pixel whose mask value is `value` (kFar when
// there is none): exact, in time linear in the pixels whatever the radius asked of it later.
std::vector<double> squared_distance_to(const std::vector<bool>& mask, bool value, int width, int height) {
    std::vector<double> dist(mask.size());
    for (std::size_t i = 0; i < mask.size(); ++i) dist[i] = mask[i] == value ? 0.0 : kFar;
    const int longest = std::max(width, height);
    std::vector<double> f(longest), d(longest), z(longest + 1);
    std::vector<int> v(longest);
    f.resize(height), d.resize(height);
    for (int x = 0; x < width; ++x) {
        for (int y = 0; y < height; ++y) f[y] = dist[static_cast<std::size_t>(y) * width + x];
        distance_1d(f, d, v, z);
        for (int y = 0; y < height; ++y) dist[static_cast<std::size_t>(y) * width + x] = d[y];
    }
    f.resize(width), d.resize(width);
    for (int y = 0; y < height; ++y) {
        std::copy_n(dist.begin() + static_cast<std::ptrdiff_t>(y) * width, width, f.begin());
        distance_1d(f, d, v, z);
        std::copy_n(d.begin(), width, dist.begin() + static_cast<std::ptrdiff_t>(y) * width);
    }
    return dist;
}

// Dilation (`grow`) or erosion of a padded mask by a disc of radius r: a pixel is set after
// dilation when a set pixel lies within r of it, kept after erosion when no unset pixel does
// (pixels beyond the frame count as unset). Distance transforms keep this linear in the pixels:
// trying every pixel of the disc took hours for a 4096 px mask and a 256 px disc.
std::vector<bool> morph(const std::vector<bool>& mask, int width, int height, int r, bool grow) {
    const double reach = static_cast<double>(r) * r;
    const std::vector<double> dist = squared_distance_to(mask, grow, width, height);
    std::vector<bool> out(mask.size());
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * width + x;
            if (grow) {
                out[i] = dist[i] <= reach;
            } else {
                const double border = std::min({x + 1, y + 1, width - x, height - y});
                out[i] = dist[i] > reach && border * border > reach;
            }
        }
    return out;
}

// Sets every unset pixel that no path of unset pixels joins to the border.
void fill_holes(std::vector<bool>& mask, int width, int height) {
    std::vector<bool> outside(mask.size(), false);
    std::vector<std::size_t> stack;
    auto visit = [&](int x, int y) {
        const std::size_t i = static_cast<std::size_t>(y) * width + x;
        if (mask[i] || outside[i]) return;
        outside[i] = true;
        stack.push_back(i);
    };
    for (int x = 0; x < width; ++x) visit(x, 0), visit(x, height - 1);
    for (int y = 0; y < height; ++y) visit(0, y), visit(width - 1, y);
    while (!stack.empty()) {
        const std::size_t i = stack.back();
        stack.pop_back();
        const int x = static_cast<int>(i % width), y = static_cast<int>(i / width);
        if (x > 0) visit(x - 1, y);
        if (x + 1 < width) visit(x + 1, y);
        if (y > 0) visit(x, y - 1);
        if (y + 1 < height) visit(x, y + 1);
    }
    for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = !outside[i];
}

}  // namespace

std::vector<bool> crown_outline(const std::vector<bool>& mask, int width, int height, int closing_px) {
    if (width <= 0 || height <= 0 || mask.size() != static_cast<std::size_t>(width) * height || closing_px < 0)
        throw Error(ExitCode::Internal, "crown_outline: mask and size disagree");
    // Padded by the disc's radius, so that the closing does not depend on the frame's edge.
    const int pad = closing_px, pw = width + 2 * pad, ph = height + 2 * pad;
    std::vector<bool> padded(static_cast<std::size_t>(pw) * ph, false);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            padded[static_cast<std::size_t>(y + pad) * pw + x + pad] = mask[static_cast<std::size_t>(y) * width + x];
    if (closing_px > 0) padded = morph(morph(padded, pw, ph, closing_px, true), pw, ph, closing_px, false);
    fill_holes(padded, pw, ph);
    std::vector<bool> out(mask.size());
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            out[static_cast<std::size_t>(y) * width + x] = padded[static_cast<std::size_t>(y + pad) * pw + x + pad];
    return out;
}

}  // namespace treelobes::render
