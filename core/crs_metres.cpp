#include "core/crs_metres.hpp"

#include "core/error.hpp"

#include <proj.h>
#include <proj_experimental.h>  // the CRS builders: alter a unit, a name; join a compound CRS

#include <memory>
#include <optional>

namespace treelobes {

namespace {

struct ContextDeleter {
    void operator()(PJ_CONTEXT* context) const { proj_context_destroy(context); }
};
struct ObjectDeleter {
    void operator()(PJ* object) const { proj_destroy(object); }
};
using Context = std::unique_ptr<PJ_CONTEXT, ContextDeleter>;
using Object = std::unique_ptr<PJ, ObjectDeleter>;

struct AxisUnit {
    double metres = 1.0;
    std::string name;
};

// The unit of axis `axis` of a CRS's coordinate system; nullopt when it has no such axis or unit.
std::optional<AxisUnit> axis_unit_of(PJ_CONTEXT* context, PJ* crs, int axis) {
    const Object cs(proj_crs_get_coordinate_system(context, crs));
    double factor = 0.0;
    const char* name = nullptr;
    if (!cs || axis >= proj_cs_get_axis_count(context, cs.get()) ||
        !proj_cs_get_axis_info(context, cs.get(), axis, nullptr, nullptr, nullptr, &factor, &name, nullptr, nullptr) || !(factor > 0.0))
        return std::nullopt;
    return AxisUnit{factor, name ? name : ""};
}

AxisUnit axis_unit(PJ_CONTEXT* context, PJ* crs, int axis, const std::string& source) {
    const std::optional<AxisUnit> unit = axis_unit_of(context, crs, axis);
    if (!unit) throw Error::input(source, "the CRS's axes name no unit");
    return *unit;
}

std::string name_of(const PJ* object) {
    const char* name = proj_get_name(object);
    return name ? name : "";
}

// The CRS with its axes in metres; its name says so when the unit changed ("NAD83 / Oregon GIC
// Lambert (ft) (in metres)"), as the name often names the old unit.
Object in_metres(PJ_CONTEXT* context, PJ* crs, double metres_per_unit, const std::string& source) {
    Object altered(proj_crs_alter_cs_linear_unit(context, crs, "metre", 1.0, "EPSG", "9001"));
    if (altered && metres_per_unit != 1.0) altered.reset(proj_alter_name(context, altered.get(), (name_of(crs) + " (in metres)").c_str()));
    if (!altered) throw Error::input(source, "PROJ cannot give the CRS's axes in metres");
    return altered;
}

bool geographic(PJ_TYPE type) {
    return type == PJ_TYPE_GEOGRAPHIC_2D_CRS || type == PJ_TYPE_GEOGRAPHIC_3D_CRS || type == PJ_TYPE_GEOCENTRIC_CRS ||
           type == PJ_TYPE_GEOGRAPHIC_CRS;
}

// A CRS as PROJ reads it (WKT 1 or 2, ESRI WKT, an EPSG code from its registry), split into its
// horizontal part and, for a compound CRS, its vertical one; a bound CRS gives its source CRS
// (its TOWGS84 clause left out). No horizontal part when PROJ cannot read the text.
struct CrsParts {
    Object horizontal, vertical;
};
CrsParts read_crs(PJ_CONTEXT* context, const std::string& text) {
    CrsParts parts;
    Object crs(proj_create(context, text.c_str()));
    if (crs && proj_get_type(crs.get()) == PJ_TYPE_BOUND_CRS) crs.reset(proj_get_source_crs(context, crs.get()));
    if (crs && proj_get_type(crs.get()) == PJ_TYPE_COMPOUND_CRS) {
        parts.horizontal.reset(proj_crs_get_sub_crs(context, crs.get(), 0));
        parts.vertical.reset(proj_crs_get_sub_crs(context, crs.get(), 1));
    } else {
        parts.horizontal = std::move(crs);
    }
    return parts;
}

Context quiet_context() {
    Context context(proj_context_create());
    proj_log_level(context.get(), PJ_LOG_NONE);
    return context;
}

// The units as PROJ reads them: across, the first axis's (angular for a geographic CRS); up, a
// compound CRS's vertical part's or a 3D CRS's third axis's.
CrsUnits units_by_proj(const std::string& text) {
    CrsUnits units;
    if (text.empty()) return units;
    const Context context = quiet_context();
    const CrsParts parts = read_crs(context.get(), text);
    const auto unit_of = [&](PJ* part, int axis) -> std::optional<CrsUnit> {
        const std::optional<AxisUnit> unit = axis_unit_of(context.get(), part, axis);
        if (!unit) return std::nullopt;
        const bool angular = geographic(proj_get_type(part));
        return CrsUnit{unit->name, angular ? 0.0 : unit->metres, angular};
    };
    if (parts.horizontal) {
        units.horizontal = unit_of(parts.horizontal.get(), 0);
        if (!parts.vertical && !geographic(proj_get_type(parts.horizontal.get()))) units.vertical = unit_of(parts.horizontal.get(), 2);
    }
    if (parts.vertical) units.vertical = unit_of(parts.vertical.get(), 0);
    return units;
}

}  // namespace

MetricCrs crs_in_metres(const Georeference& georef, const std::string& source) {
    if (georef.crs_wkt.empty()) throw Error::input(source, "no CRS: the coordinates' unit is unknown");
    const Context context = quiet_context();
    const CrsParts parts = read_crs(context.get(), georef.crs_wkt);
    PJ* horizontal = parts.horizontal.get();
    PJ* vertical = parts.vertical.get();
    if (!horizontal) throw Error::input(source, "PROJ cannot read the CRS (" + georef.crs_wkt.substr(0, 60) + ")");
    if (proj_get_type(horizontal) != PJ_TYPE_PROJECTED_CRS) {
        if (geographic(proj_get_type(horizontal)))
            throw Error::input(source,
                               "the CRS is geographic (degrees): reproject it to a projected CRS, which a change of unit cannot do");
        throw Error::input(source, "the CRS is not a projected one");
    }
    MetricCrs metric;
    const AxisUnit across = axis_unit(context.get(), horizontal, 0, source);
    metric.horizontal = across.metres;
    metric.horizontal_unit = across.name;
    Object result = in_metres(context.get(), horizontal, metric.horizontal, source);
    const Object cs(proj_crs_get_coordinate_system(context.get(), horizontal));
    if (vertical) {
        const AxisUnit up = axis_unit(context.get(), vertical, 0, source);
        metric.vertical = up.metres;
        metric.vertical_unit = up.name;
        metric.vertical_source = "vertical CRS";
        const Object vertical_metres = in_metres(context.get(), vertical, metric.vertical, source);
        const std::string name = name_of(result.get()) + " + " + name_of(vertical_metres.get());
        result.reset(proj_create_compound_crs(context.get(), name.c_str(), result.get(), vertical_metres.get()));
        if (!result) throw Error::input(source, "PROJ cannot join the CRS's parts in metres");
    } else if (cs && proj_cs_get_axis_count(context.get(), cs.get()) == 3) {
        const AxisUnit up = axis_unit(context.get(), horizontal, 2, source);
        metric.vertical = up.metres;
        metric.vertical_unit = up.name;
        metric.vertical_source = "CRS axes";
    } else {
        metric.vertical = metric.horizontal;
        metric.vertical_unit = metric.horizontal_unit;
        metric.vertical_source = "assumed as horizontal";
    }
    const char* wkt = result ? proj_as_wkt(context.get(), result.get(), PJ_WKT1_GDAL, nullptr) : nullptr;
    if (!wkt) throw Error::input(source, "PROJ cannot write the CRS in metres as WKT");
    metric.wkt = wkt;
    return metric;
}

CrsUnits crs_units_of(const Georeference& georef) {
    CrsUnits units{crs_horizontal_unit(georef.crs_wkt), crs_vertical_unit(georef.crs_wkt)};
    if (!units.horizontal) units.horizontal = epsg_linear_unit(georef.linear_unit_code);
    if (!units.vertical) units.vertical = epsg_linear_unit(georef.vertical_unit_code);
    return units.horizontal ? units : units_by_proj(georef.crs_wkt);
}

void convert_to_metres(PointCloud& cloud, const MetricCrs& metric) {
    const Eigen::Vector3d factor(metric.horizontal, metric.horizontal, metric.vertical);
    for (Eigen::Vector3f& p : cloud.positions) p = p.cast<double>().cwiseProduct(factor).cast<float>();
    cloud.origin = cloud.origin.cwiseProduct(factor);
    cloud.source.las_scale = cloud.source.las_scale.cwiseProduct(factor);
    cloud.source.las_offset = cloud.source.las_offset.cwiseProduct(factor);
    cloud.georef = Georeference{};
    cloud.georef.crs_wkt = metric.wkt;
}

}  // namespace treelobes
