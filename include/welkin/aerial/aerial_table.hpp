// SPDX-License-Identifier: Apache-2.0
// Aerial perspective from one viewpoint as a table of view direction and distance, for
// renderers that apply it per shading point (the Blender add-on's material node group).
//
// Derivation. The air between a camera at a fixed point c and a surface point p depends
// only on the ray from c towards p and on the distance |p - c|: with the sun at infinity,
// the integrand of aerial_perspective.hpp,
//     L_in(d) = integral_0^d T(t) E_sun [T_sun(x(t)) (sigma_R P_R(nu) + sigma_M P_M(nu))
//                                       + (sigma_R + sigma_M) Psi_ms(x(t))] dt,
//     T(d)    = exp(-integral_0^d sigma_t(x(t)) dt),       x(t) = c + t v,
// is a function of the unit direction v and of d alone once c, the sun and the atmosphere
// are fixed (nu = v . s). So for one frame (one camera position, one sun) the passes of
// every pixel of any camera at c, perspective or panoramic, are lookups in a 3-D table
// of (direction, distance), whatever the geometry: Hillaire 2020's froxel volume with the
// screen replaced by the sphere of directions, so that it needs no depth buffer.
//
// Layout (what a shader samples; all coordinates in [0, 1]):
//  * azimuth phi = atan2(v_y, v_x) in Blender's world frame: u = phi / (2 pi) + 1/2; texel i
//    (0..azimuths-1) holds u_i = (i + 1/2) / azimuths, so linear filtering with a
//    repeating texture wraps around exactly;
//  * elevation theta = asin(v_z): e = 1/2 + 1/2 sign(theta) sqrt(|theta| / (pi/2)) (Hillaire
//    2020 sec. 5.3's sky-view mapping: rows crowd at the horizon, where the path through the
//    low, dense air changes fastest with elevation); row j (0..elevations-1) holds
//    e_j = j / (elevations - 1), so the nadir and the zenith are rows;
//  * distance: slice k (0..slices-1) at d_k = d_0 (exp(k c) - 1), c = ln(1 + d_max / d_0) /
//    (slices - 1), with d_0 = linear_distance_m and d_max = max_distance_m: evenly spaced
//    (about d_0 c apart) well inside d_0, growing geometrically (by the factor e^c) beyond
//    it, so that the relative spacing is bounded at every distance from metres to the
//    atmosphere's width (a quadratic spacing fitted to the whole atmosphere would leave the
//    first kilometres in one slice). Slice 0 is d = 0: L = 0, T = 1. A distance d between
//    d_k and d_k+1 is read linearly in d between them, with the weight
//    w = ((1 + d / d_0) e^(-k c) - 1) / (e^c - 1); beyond max_distance_m the last slice
//    holds. The error of reading in-scattering L(d) = A (1 - e^(-sigma d)) linearly
//    between slices is at most (e^c - 1)^2 / 8 of it relative (the second derivative
//    over the spacing), 0.6 % for 48 slices over 100 m .. 2000 km.
// Each entry holds the passes' RGB (aerial_perspective.hpp: L_in times the exposure, and
// the sunlit-surface transmittance) with T stored as optical depth, -ln T, so that linear
// interpolation between deep slices does not band (as the froxel volume does).
//
// How it is computed: each direction's ray is marched once through the slices
// (steps_per_slice energy-conserving steps per slice: src/aerial/air_march.hpp, derived in
// aerial_perspective.cpp), so the table of a frame costs directions x slices x steps
// samples. Rays below the horizon go on under the ground sphere with the ground's air, as
// aerial_perspective() treats such points.
//
// Limits: one viewpoint per table, so an orthographic camera (whose rays start across its
// film) is approximated by its centre; surfaces beyond max_distance_m read the last slice.
// Threads: TBB; results do not depend on the thread count.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/luts.hpp"
#include "welkin/base/progress.hpp"

namespace welkin {

struct AerialTableLayout {
    int azimuths = 128, elevations = 64, slices = 48;
    double max_distance_m = 0.0;       // in [1e-3, 1e9] m: below linear_distance_m, evenly spaced
    double linear_distance_m = 100.0;  // > 0
    int steps_per_slice = 4;

    // Throws InvalidArgument naming `parameter`.<field> and its range.
    void validate(const std::string& parameter = "table") const;

    // The texel coordinates of a unit direction (u: azimuth, e: elevation), as above.
    static double azimuth_coordinate(const glm::dvec3& v);
    static double elevation_coordinate(const glm::dvec3& v);
    // The unit direction of texel (i, j).
    glm::dvec3 direction(int i, int j) const;
    // The distance of slice k, m, and the growth exponent c.
    double slice_distance(int k) const;
    double slice_exponent() const;
};

struct AerialTable {
    AerialTableLayout layout;
    // (slices, elevations, azimuths, 3), slice 0 first, row j = e_j: in-scattering (RGB,
    // times the exposure) and optical depth -ln T (RGB, >= 0, at most 80).
    std::vector<float> inscatter, optical_depth;
};

// The table for a viewpoint `camera_position` (world frame, m; the planet centre at
// `planet_centre`) and the unit `sun_direction`, in `atmosphere` (whose LUTs `luts` are).
// Throws InvalidArgument for a bad layout or a non-finite position.
AerialTable aerial_table(const Atmosphere& atmosphere, const AtmosphereLuts& luts,
                         const glm::dvec3& planet_centre, const glm::dvec3& camera_position,
                         const glm::dvec3& sun_direction, double exposure, const AerialTableLayout& layout,
                         Progress* progress = nullptr, ColorSpace color_space = ColorSpace::Rec709);

// The same passes for one camera, as a table over its screen and the distance: what a
// renderer samples when it knows where a shading point lies in the frame (Blender's Camera
// Data > View Vector, or Texture Coordinate > Window) and its distance (Camera Data > View
// Distance, or View Z Depth for an orthographic camera, whose rays start on its plane).
// Cheaper per sample than the direction table's angles, and with no directions to spare:
// the screen is all a frame sees.
//
// Layout: a lattice, periodic in every axis, so that a shader reaches a texel with one
// logarithm, one snap and one multiply-add and reads it with a repeating texture.
//  * Screen axes. Lattice column i lies at x_i = (first_x + i + 1/2) spacing_x in the
//    coordinate (Window: x and y in [0, 1] left to right and bottom to top; View Vector: the
//    unit camera-space direction's x (right) and y (up)), row j at y_j likewise. The
//    lattice covers the frame widened by margin_x and margin_y on each side (where a pixel
//    filter's samples fall) with columns - 2 and rows - 2 spacings, so that the last
//    spacing, where a repeating texture wraps, lies outside it. Texel column
//    (first_x + i) mod columns holds column i: the texture coordinate is x / (columns
//    spacing_x) plus any integer.
//  * Distance. Slice k lies at d_k = ratio^(first_exponent + k) scene units (unit_m metres
//    each), k = 0 .. slices - 1, from a slice below the camera's clip start to one beyond
//    the farthest distance it sees (clip end along the frame's most oblique ray), so that
//    the slice of a sample is s = floor(t), t = log_ratio(d), with no clamping. Texel row
//    (s rows + first_y + j) mod (slices rows), bottom row first, holds slice s's row j: the
//    texture coordinate is y / (slices rows spacing_y) + s / slices. With tau = t / slices
//    = log_(ratio^slices) d, snap(tau, (1, 1 / slices)) = (floor tau, s / slices) is the
//    part of (u, v) that the slice adds (floor tau is an integer: no change to u).
//  * Between slices, linearly in t: each pass is a mix (1 - tau) P + tau Q of two values per
//    texel (textures()), whose line through the slice's own value and the next slice's
//    value is reached at tau = t / slices. Reading linearly in log d errs by at most about
//    ln(ratio)^2 / 8 of the value (L grows like d at short range); 0.24 % for 1.15.
// The ray of lattice point (i, j) is CameraRays::at_view_vector or at_screen's: exact for
// every camera type, an orthographic camera's rays starting across its plane.
//
// Cost: columns x rows x slices x steps_per_slice samples (0.17 M for 32 x 48 at ratio
// 1.15 from 0.1 m to 1000 km). The rows are the finer axis: near the horizon a row's step
// moves a long ray's altitude by a fraction of the haze's scale height.

// What the shader knows of a sample's place in the frame (see above).
enum class ScreenCoordinate { Window, ViewVector };

struct AerialScreenTableLayout {
    ScreenCoordinate coordinate = ScreenCoordinate::Window;  // ViewVector: perspective only
    int columns = 32, rows = 48;                             // >= 4
    double margin_x = 0.02, margin_y = 0.02;                 // Window fractions beyond each edge, [0, 1]
    double unit_m = 1.0;                                     // the shader's distance unit, m
    double ratio = 1.15;                                     // distance growth per slice, (1, 10]
    int max_slices = 256;                                    // the ratio grows rather than exceed it
    int steps_per_slice = 1;
    // Throws InvalidArgument naming `parameter`.<field> and its range.
    void validate(const std::string& parameter = "table") const;
};

// The lattice of one camera's table (see above), derived from the layout and the camera.
struct AerialScreenLattice {
    ScreenCoordinate coordinate = ScreenCoordinate::Window;
    int columns = 0, rows = 0, slices = 0;
    double spacing_x = 0.0, spacing_y = 0.0;
    int first_x = 0, first_y = 0;
    double ratio = 1.15;  // may exceed the layout's, to keep to max_slices
    int first_exponent = 0;
    double unit_m = 1.0;

    double x(int i) const { return (double(first_x + i) + 0.5) * spacing_x; }
    double y(int j) const { return (double(first_y + j) + 0.5) * spacing_y; }
    double slice_distance_m(int k) const;
    // The texel holding lattice column i, and row j of slice k (bottom row first).
    int texel_column(int i) const;
    int texel_row(int j, int k) const;
};

struct AerialScreenTable {
    AerialScreenLattice lattice;
    // (slices, rows, columns, 3), slice k, row j (y_j, upwards), column i: in-scattering
    // (RGB, times the exposure) and transmittance (RGB, in [0, 1]).
    std::vector<float> inscatter, transmittance;

    // The three RGBA float textures the shader reads, (3, slices x rows, columns, 4), texels
    // placed as above. With A = 1 - T, t = log_ratio d, n = slices and the steps to the next
    // slice dL = L_(k+1) - L_k, dA likewise (0 in the last slice), slice s = first_exponent
    // + k, each pass's line L_k + (t - s) dL is held as its values at tau = t / n = 0 and 1:
    //     texture 0: L_k - s dL,        alpha: (A_k + (n - s) dA).r
    //     texture 1: L_k + (n - s) dL,  alpha: (A_k + (n - s) dA).g
    //     texture 2: A_k - s dA,        alpha: (A_k + (n - s) dA).b
    // so that L = mix(tex0, tex1, tau) and A = mix(tex2, (tex0.a, tex1.a, tex2.a), tau),
    // mix(p, q, f) = (1 - f) p + f q: at t = s the slice's own values, linear in t up to
    // the next. texture_floats() floats, written into `out` (every one of them).
    std::size_t texture_floats() const;
    void textures(std::span<float> out) const;
    std::vector<float> textures() const;
};

// The table of `view`'s camera at its render resolution and clip range (view.options are
// not used); `luts` built from view.atmosphere with view.luts. Throws InvalidArgument for a
// bad layout (naming table.<field>) or view, or a View Vector table of a camera that is not
// perspective.
AerialScreenTable aerial_screen_table(const AerialView& view, const AtmosphereLuts& luts,
                                      const AerialScreenTableLayout& layout, Progress* progress = nullptr);

}  // namespace welkin
