// SPDX-License-Identifier: Apache-2.0
// The aerial tables (aerial_table.hpp): the direction table (the mapping, then one march
// per direction) and the screen table (one march per lattice point of the camera's
// screen), both marched by air_march.hpp's slice marcher.
#include "welkin/aerial/aerial_table.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "air_march.hpp"
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"

namespace welkin {

using aerial_march::air_ray;
using aerial_march::AirRay;
using aerial_march::march_grid;
using aerial_march::optical_depth_of;
using aerial_march::PassColour;

namespace {

// Offset of entry (slice k, row j, column i) of a (slices, rows, columns, 3) table.
std::size_t table_offset(int k, int j, int i, int rows, int columns) {
    return ((std::size_t(k) * std::size_t(rows) + std::size_t(j)) * std::size_t(columns) + std::size_t(i)) *
           3;
}

// A table of a x b x c entries must stay within 64 Mi of them.
void require_table_entries(const std::string& parameter, int a, int b, int c) {
    if (double(a) * b * c > 64.0 * 1024 * 1024)
        throw InvalidArgument(parameter, fmt::format("{} x {} x {} entries: at most 64 Mi", a, b, c));
}

}  // namespace

// The direction table (aerial_table.hpp): the mapping, then one march per direction.
void AerialTableLayout::validate(const std::string& parameter) const {
    const std::string p = parameter.empty() ? parameter : parameter + ".";
    require_in_range(p + "azimuths", azimuths, 4, 4096);
    require_in_range(p + "elevations", elevations, 3, 4096);
    require_in_range(p + "slices", slices, 2, 1024);
    require_in_range(p + "steps_per_slice", steps_per_slice, 1, 256);
    require_in_range(p + "linear_distance_m", linear_distance_m, 1e-3, 1e9, "m");
    require_in_range(p + "max_distance_m", max_distance_m, 1e-3, 1e9, "m");
    require_table_entries(parameter.empty() ? "slices" : parameter, azimuths, elevations, slices);
}

double AerialTableLayout::azimuth_coordinate(const glm::dvec3& v) {
    return std::atan2(v.y, v.x) / kTwoPi + 0.5;
}

double AerialTableLayout::elevation_coordinate(const glm::dvec3& v) {
    const double theta = std::asin(clamp_cosine(v.z / glm::length(v)));
    const double a = std::sqrt(std::abs(theta) / (0.5 * kPi));
    return 0.5 + 0.5 * (theta < 0.0 ? -a : a);
}

glm::dvec3 AerialTableLayout::direction(int i, int j) const {
    const double phi = kTwoPi * ((double(i) + 0.5) / double(azimuths) - 0.5);
    const double e = 2.0 * double(j) / double(elevations - 1) - 1.0;  // in [-1, 1]
    const double theta = (e < 0.0 ? -1.0 : 1.0) * e * e * 0.5 * kPi;
    return {std::cos(theta) * std::cos(phi), std::cos(theta) * std::sin(phi), std::sin(theta)};
}

double AerialTableLayout::slice_exponent() const {
    return std::log1p(max_distance_m / linear_distance_m) / double(slices - 1);
}

double AerialTableLayout::slice_distance(int k) const {
    return linear_distance_m * std::expm1(double(k) * slice_exponent());
}

AerialTable aerial_table(const Atmosphere& atmosphere, const AtmosphereLuts& luts,
                         const glm::dvec3& planet_centre, const glm::dvec3& camera_position,
                         const glm::dvec3& sun_direction, double exposure, const AerialTableLayout& layout,
                         Progress* progress, ColorSpace color_space) {
    layout.validate();
    for (int c = 0; c < 3; ++c) {
        require_finite("camera_position", camera_position[c]);
        require_finite("sun_direction", sun_direction[c]);
    }
    require_in_range("exposure", exposure, 1e-12, 1e6);
    if (!(glm::length(sun_direction) > 0.5)) throw InvalidArgument("sun_direction", "must be a unit vector");
    const glm::dvec3 sun = glm::normalize(sun_direction);
    const PassColour colour(atmosphere, exposure, color_space);
    const int na = layout.azimuths, ne = layout.elevations, nk = layout.slices;
    AerialTable table{layout, {}, {}};
    table.inscatter.assign(std::size_t(na) * ne * nk * 3, 0.0f);
    table.optical_depth.assign(table.inscatter.size(), 0.0f);
    std::vector<double> distances(std::size_t(nk - 1));  // slice 0: d = 0, L = 0, T = 1
    for (int k = 1; k < nk; ++k) distances[std::size_t(k - 1)] = layout.slice_distance(k);
    march_grid(
        luts, colour, layout.steps_per_slice, na, ne, distances, progress,
        [&](int i, int j, std::vector<double>&) {
            return AirRay{camera_position - planet_centre, layout.direction(i, j), sun};
        },
        [&](int i, int j, const std::vector<float>& L, const std::vector<float>& T) {
            for (int k = 1; k < nk; ++k) {
                const std::size_t o = table_offset(k, j, i, ne, na);
                for (int c = 0; c < 3; ++c) {
                    table.inscatter[o + c] = L[std::size_t(k - 1) * 3 + c];
                    table.optical_depth[o + c] = optical_depth_of(T[std::size_t(k - 1) * 3 + c]);
                }
            }
        });
    return table;
}

// The screen table (aerial_table.hpp): one march per lattice point of the camera's screen.
void AerialScreenTableLayout::validate(const std::string& parameter) const {
    const std::string p = parameter.empty() ? parameter : parameter + ".";
    require_in_range(p + "columns", columns, 4, 4096);
    require_in_range(p + "rows", rows, 4, 4096);
    require_in_range(p + "margin_x", margin_x, 0.0, 1.0);
    require_in_range(p + "margin_y", margin_y, 0.0, 1.0);
    require_in_range(p + "unit_m", unit_m, 1e-6, 1e6, "m");
    require_in_range(p + "ratio", ratio, 1.001, 10.0);
    require_in_range(p + "max_slices", max_slices, 8, 1024);
    require_in_range(p + "steps_per_slice", steps_per_slice, 1, 256);
    require_table_entries(p + "max_slices", columns, rows, max_slices);
}

namespace {

// The lattice along one axis over [lo, hi]: points - 2 spacings across it, the first point
// half a spacing past a multiple of the spacing at or below lo (so the last lies at or
// beyond hi).
void lattice_axis(double lo, double hi, int points, double& spacing, int& first) {
    spacing = (hi - lo) / double(points - 2);
    first = int(std::floor(lo / spacing - 0.5));
}

}  // namespace

double AerialScreenLattice::slice_distance_m(int k) const {
    return unit_m * std::pow(ratio, double(first_exponent + k));
}

int AerialScreenLattice::texel_column(int i) const { return wrap_index(first_x + i, columns); }

int AerialScreenLattice::texel_row(int j, int k) const {
    return int(wrap_index((long long)(first_exponent + k) * rows + first_y + j, (long long)slices * rows));
}

std::size_t AerialScreenTable::texture_floats() const {
    return 3 * std::size_t(lattice.slices) * std::size_t(lattice.rows) * std::size_t(lattice.columns) * 4;
}

std::vector<float> AerialScreenTable::textures() const {
    std::vector<float> out(texture_floats());
    textures(out);
    return out;
}

void AerialScreenTable::textures(std::span<float> out) const {
    if (out.size() != texture_floats())
        throw InvalidArgument("textures",
                              fmt::format("{} floats given, {} needed", out.size(), texture_floats()));
    const AerialScreenLattice& g = lattice;
    const std::size_t S = std::size_t(g.slices), R = std::size_t(g.rows), C = std::size_t(g.columns);
    const std::size_t texture = S * R * C * 4;
    const double n = double(g.slices);
    std::vector<std::size_t> column(C);
    for (std::size_t i = 0; i < C; ++i) column[i] = std::size_t(g.texel_column(int(i))) * 4;
    tbb::parallel_for(std::size_t(0), S, [&](std::size_t k) {
        const bool last = k + 1 == S;  // read flat: no distance seen lies beyond it
        const double s = double(g.first_exponent) + double(k);
        for (std::size_t j = 0; j < R; ++j) {
            const std::size_t row = std::size_t(g.texel_row(int(j), int(k))) * C * 4;
            for (std::size_t i = 0; i < C; ++i) {
                const std::size_t at = ((k * R + j) * C + i) * 3, next = at + R * C * 3;
                const std::size_t texel = row + column[i];
                for (std::size_t c = 0; c < 3; ++c) {
                    const double L = inscatter[at + c], A = 1.0 - double(transmittance[at + c]);
                    const double dL = last ? 0.0 : inscatter[next + c] - L;
                    const double dA = last ? 0.0 : (1.0 - double(transmittance[next + c])) - A;
                    out[texel + c] = float(L - s * dL);
                    out[texture + texel + c] = float(L + (n - s) * dL);
                    out[2 * texture + texel + c] = float(A - s * dA);
                    out[c * texture + texel + 3] = float(A + (n - s) * dA);
                }
            }
        }
    });
}

AerialScreenTable aerial_screen_table(const AerialView& view, const AtmosphereLuts& luts,
                                      const AerialScreenTableLayout& layout, Progress* progress) {
    view.validate();
    layout.validate("table");
    const CameraRays rays(view.camera, view.width, view.height);
    const bool view_vector = layout.coordinate == ScreenCoordinate::ViewVector;
    if (view_vector && rays.type() != CameraType::Perspective)
        throw InvalidArgument("table.coordinate",
                              fmt::format("\"view_vector\" needs a perspective camera, this one is {}",
                                          camera_type_name(view.camera.type)));

    // The frame widened by the margins, in the coordinate, and the farthest distance seen
    // (Cycles clips a perspective camera's rays at clip end in depth, so its oblique rays
    // reach farther): from the widened frame's edges, sampled finely (the extremes of a
    // view vector over a straight edge of the film lie at its ends or where it crosses an
    // axis, both within a sample's spacing of a sample).
    double x_lo = 1e300, x_hi = -1e300, y_lo = 1e300, y_hi = -1e300, reach = 1.0;
    constexpr int kEdge = 256;
    const double mx = layout.margin_x, my = layout.margin_y;
    for (int e = 0; e < 4; ++e)
        for (int q = 0; q <= kEdge; ++q) {
            const double f = double(q) / kEdge;
            const double wx = e < 2 ? -mx + (1.0 + 2.0 * mx) * f : (e == 2 ? -mx : 1.0 + mx);
            const double wy = e < 2 ? (e == 0 ? -my : 1.0 + my) : -my + (1.0 + 2.0 * my) * f;
            const CameraRays::Ray r = rays.at_screen(wx, 1.0 - wy);  // Window's y is upwards
            double cx = wx, cy = wy;
            if (view_vector) {
                const glm::dvec3 v = rays.view_vector(r.direction);
                cx = v.x;
                cy = v.y;
            }
            x_lo = std::min(x_lo, cx);
            x_hi = std::max(x_hi, cx);
            y_lo = std::min(y_lo, cy);
            y_hi = std::max(y_hi, cy);
            reach = std::max(reach, r.distance_per_depth);  // 1 but for perspective cameras
        }
    const double slack_x = 1e-3 * (x_hi - x_lo), slack_y = 1e-3 * (y_hi - y_lo);
    AerialScreenTable table;
    AerialScreenLattice& g = table.lattice;
    g.coordinate = layout.coordinate;
    g.columns = layout.columns;
    g.rows = layout.rows;
    lattice_axis(x_lo - slack_x, x_hi + slack_x, g.columns, g.spacing_x, g.first_x);
    lattice_axis(y_lo - slack_y, y_hi + slack_y, g.rows, g.spacing_y, g.first_y);

    // Slices: one below the clip start and one beyond the farthest distance besides those
    // that bracket them, so that a shader's float rounding of log d near either end still
    // reads its own slice, never the other end's across the wrap.
    g.unit_m = layout.unit_m;
    const double near = view.camera.clip_start_m / layout.unit_m;
    const double far = view.camera.clip_end_m * reach / layout.unit_m;
    g.ratio = layout.ratio;
    auto span = [&](double ratio, int& first) {
        first = int(std::floor(std::log(near) / std::log(ratio))) - 1;
        return int(std::ceil(std::log(far) / std::log(ratio))) + 1 - first + 1;
    };
    g.slices = span(g.ratio, g.first_exponent);
    if (g.slices > layout.max_slices) {
        g.ratio = std::pow(far / near, 1.0 / double(layout.max_slices - 5));
        g.slices = span(g.ratio, g.first_exponent);
    }
    require_table_entries("table.max_slices", g.columns, g.rows, g.slices);

    const glm::dvec3 sun = view.origin.sun_direction;
    const PassColour colour(view.atmosphere, view.exposure, view.color_space);
    const int nx = g.columns, ny = g.rows, nk = g.slices;
    table.inscatter.assign(std::size_t(nx) * ny * nk * 3, 0.0f);
    table.transmittance.assign(table.inscatter.size(), 1.0f);
    // Distances along each ray from its origin: the camera's position, or for an
    // orthographic camera its plane (where Blender's View Z Depth is the distance).
    std::vector<double> distances(static_cast<std::size_t>(nk));
    for (int k = 0; k < nk; ++k) distances[std::size_t(k)] = g.slice_distance_m(k);
    march_grid(
        luts, colour, layout.steps_per_slice, nx, ny, distances, progress,
        [&](int i, int j, std::vector<double>&) {
            if (!view_vector) return air_ray(view, rays.at_screen(g.x(i), 1.0 - g.y(j)), sun);
            // Lattice points beyond the unit disc (corners of a very wide frame's lattice,
            // outside the frame) take the nearest direction ahead.
            double vx = g.x(i), vy = g.y(j);
            const double r2 = vx * vx + vy * vy, most = 1.0 - 1e-6;
            if (r2 > most) {
                const double f = std::sqrt(most / r2);
                vx *= f;
                vy *= f;
            }
            return air_ray(view, rays.at_view_vector(vx, vy), sun);
        },
        [&](int i, int j, const std::vector<float>& L, const std::vector<float>& T) {
            for (int k = 0; k < nk; ++k) {
                const std::size_t o = table_offset(k, j, i, ny, nx);
                std::copy_n(&L[std::size_t(k) * 3], 3, &table.inscatter[o]);
                std::copy_n(&T[std::size_t(k) * 3], 3, &table.transmittance[o]);
            }
        });
    return table;
}

}  // namespace welkin
