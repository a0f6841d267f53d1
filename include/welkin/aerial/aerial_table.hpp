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
// (steps_per_slice energy-conserving steps per slice, aerial_perspective.cpp), so the table
// of a frame costs directions x slices x steps samples. Rays below the horizon go on under
// the ground sphere with the ground's air, as aerial_perspective() treats such points.
//
// Limits: one viewpoint per table, so an orthographic camera (whose rays start across its
// film) is approximated by its centre; surfaces beyond max_distance_m read the last slice.
// Threads: TBB; results do not depend on the thread count.
#pragma once

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
    double max_distance_m = 0.0;       // > linear_distance_m
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
                         Progress* progress = nullptr);

// The same passes for one camera, as a table over its screen and the distance: what a
// renderer samples when it knows a shading point's screen position (Blender's Texture
// Coordinate > Window) and its distance (Camera Data > View Distance), which is cheaper per
// sample than the direction table's angles and needs no direction crowding, since the
// screen is all a frame sees.
//
// Layout (all of it an affine function of the screen position and of log d, so that a
// shader reaches a texel in a few multiply-adds):
//  * grid point (i, j) at screen coordinates (screen_x(i), screen_y(j)) (camera.hpp's:
//    left to right, top to bottom), columns evenly spaced from -margin_x to 1 + margin_x and
//    rows from -margin_y to 1 + margin_y, so that samples a pixel filter takes just outside
//    the frame still fall between grid points; its ray is CameraRays::at_screen's (an
//    orthographic camera's starts on the camera's plane: exact, not from the centre);
//  * slice k (0..slices-1) at distance d_k = first_distance_m ratio^k along the ray: purely
//    geometric, so the slice coordinate log_ratio(d / first_distance_m) is one logarithm,
//    and reading linearly in it between slices errs by at most about ln(ratio)^2 / 8 of
//    the value (L grows like d^1 at short range, e^(k ln ratio) in k; 0.24 % for 1.15).
//    Surfaces nearer than first_distance_m read slice 0, those beyond the last slice the
//    last slice.
// Each entry holds the passes' RGB: in-scattering times the exposure and the transmittance
// (read linearly, not as optical depth: over a slice 15 % deep, T = e^-tau bends by less
// than 0.1 % of 1 between slices).
//
// Cost: columns x rows x slices x steps_per_slice samples; the default 32 x 48 grid at
// ratio 1.15 from 10 m to 1000 km (85 slices), 1 step each, is 0.13 M samples. The rows
// are the finer axis: near the horizon a row's step in elevation moves a long ray's
// altitude by a fraction of the haze's scale height.
struct AerialScreenTableLayout {
    int columns = 32, rows = 48, slices = 85;
    double margin_x = 0.02, margin_y = 0.02;  // screen fractions beyond each edge, >= 0
    double first_distance_m = 10.0;           // > 0
    double ratio = 1.15;                      // > 1
    int steps_per_slice = 2;
    // Throws InvalidArgument naming `parameter`.<field> and its range.
    void validate(const std::string& parameter = "table") const;
    double screen_x(int i) const;
    double screen_y(int j) const;
    double slice_distance(int k) const;  // m
};

struct AerialScreenTable {
    AerialScreenTableLayout layout;
    // (slices, rows, columns, 3), slice 0 and the top row (screen y = -margin_y) first:
    // in-scattering (RGB, times the exposure) and transmittance (RGB, in [0, 1]).
    std::vector<float> inscatter, transmittance;

    // The table as four RGBA float textures for a shader that reads one slice's texels and
    // goes linearly to the next in t = first_index + k + f (f the fraction of the way from
    // slice k to k + 1; first_index any integer, e.g. log_ratio of first_distance_m in the
    // shader's unit): (4, slices x rows, columns, 4), each texture's rows bottom first
    // (OpenGL's and Blender's order) with slice k in rows [k rows, (k + 1) rows), alpha 1:
    //     step_L = L_(k+1) - L_k,            L_k - (first_index + k) step_L,
    //     step_A = A_(k+1) - A_k (A = 1 - T), A_k - (first_index + k) step_A,
    // in the order (L at t = 0, step_L, A at t = 0, step_A), so that the passes are
    // value + t step, one multiply-add per pass. Slice 0 and the last slice have step 0:
    // distances before slice 1 read slice 0's passes, beyond the last slice the last's.
    std::vector<float> step_textures(int first_index) const;
};

// The table of `view`'s camera at its render resolution (view.options are not used);
// `luts` built from view.atmosphere with view.luts. Throws InvalidArgument for a bad
// layout (naming table.<field>) or view.
AerialScreenTable aerial_screen_table(const AerialView& view, const AtmosphereLuts& luts,
                                      const AerialScreenTableLayout& layout, Progress* progress = nullptr);

}  // namespace welkin
