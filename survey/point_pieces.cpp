#include "survey/point_pieces.hpp"

namespace treelobes::survey {

namespace {

template <typename T>
void append_values(std::vector<T>& into, const std::vector<T>& from) {
    into.insert(into.end(), from.begin(), from.end());
}

}  // namespace

std::string attribute_signature(const PointCloud& cloud) {
    std::string signature;
    for (const std::string& name : cloud.attribute_names()) signature += name + ";";
    for (const ExtraAttribute& extra : cloud.extras) signature += extra.name + ":" + attribute_type_name(extra.type) + ";";
    return signature;
}

void append_points(PointCloud& into, const PointCloud& piece) {
    const Eigen::Vector3d shift = piece.origin - into.origin;
    for (const Eigen::Vector3f& p : piece.positions) into.positions.push_back((p.cast<double>() + shift).cast<float>());
    append_values(into.intensity, piece.intensity);
    append_values(into.return_number, piece.return_number);
    append_values(into.number_of_returns, piece.number_of_returns);
    append_values(into.classification, piece.classification);
    append_values(into.rgb, piece.rgb);
    append_values(into.gps_time, piece.gps_time);
    for (std::size_t k = 0; k < into.extras.size(); ++k) append_values(into.extras[k].values, piece.extras[k].values);
}

}  // namespace treelobes::survey
