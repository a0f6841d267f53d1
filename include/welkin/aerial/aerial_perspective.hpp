// SPDX-License-Identifier: Apache-2.0
// Aerial perspective: the air between a camera and the surfaces it renders (Hillaire 2020,
// "A Scalable and Production Ready Sky and Atmosphere Rendering Technique", sec. 5.6).
//
// A surface at distance d along a view ray is seen through the air as
//     L_seen = T(d) L_surface + L_in(d),
// with T(d) the transmittance of the path and L_in(d) the light the air scatters into it
// (single scattering of the sun, with the planet's shadow, plus Hillaire's multiple-
// scattering term; the same integrand as the sky, inscattering.hpp):
//     L_in(d) = integral_0^d T(t) E_sun [T_sun(t) (sigma_R P_R + sigma_M P_M)
//                                       + (sigma_R + sigma_M) Psi_ms(t)] dt.
// The passes hold exactly these two, per pixel: `Welkin.AerialInscatter` = L_in (RGB) and
// `Welkin.AerialTransmittance` = T (RGB), so that a compositor's Image x T + Inscatter is
// the hazed render. Sun transmittance and Psi_ms come from the atmosphere's LUTs
// (atmosphere/luts.hpp); terrain shadows on the air (light shafts) are not modelled.
//
// Units and colour, as the sky's: L_in is linear Rec.709 in W m^-2 sr^-1 (CIE 1931
// weighted, without the 683 lm/W factor; color.hpp, lambda power -3, the sky's
// conversion), multiplied by the scene's exposure. T is dimensionless and is the
// transmittance a sunlit surface sees: per Rec.709 channel k,
//     T_k = rgb_k(E_sun(lambda) T(lambda)) / rgb_k(E_sun(lambda))
// with the sun's conversion (lambda power 0), clamped to [0, 1]; T = 1 gives exactly 1.
//
// Two ways to the passes, behind one call (aerial_perspective()):
//  * "froxel" (Hillaire's camera volume): a froxel_width x froxel_height x froxel_slices
//    grid over the camera's screen (columns at screen coordinates i / (width - 1), so the
//    image edges are columns) and its depth. Depth slices are spaced quadratically,
//    z_k = z_max (k / N)^2, k = 1..N (dense near the camera, where haze builds fastest
//    relative to its value), and z_max is fitted to the depth buffer unless given: the
//    depth below which 99.9 % of the non-sky pixels lie, and no further than the farthest
//    depth at which a column's ray leaves the atmosphere (beyond it nothing changes). The
//    rarer deeper pixels (a far ridge's last pixels, the Moon) are marched one by one as
//    by "raymarch", so that they do not stretch every slice. The volume is built by
//    marching each column's ray through the slices (steps_per_slice sub-steps each). A pixel reads it
//    bilinearly across the screen and linearly in depth between its two slices (with L = 0, T = 1 at depth
//    0); the transmittance is interpolated as optical depth, -ln T, so that exponential fall-off across deep
//    slices does not band.
//  * "raymarch": every pixel's ray marched to its own depth (raymarch_steps uniform steps,
//    each integrated in Hillaire's energy-conserving form), the reference the froxels are
//    tested and benchmarked against.
//
// Depth is Blender's Z pass (camera.hpp): along the view axis for perspective and
// orthographic cameras, along the ray for panoramic ones; all three camera types are
// supported by both ways (a full panorama needs more froxel columns than 32 x 32, which
// it spreads over the whole sphere; 256 x 128 is tested).
//
// Sky pixels: a depth of +infinity, or at or beyond
// aerial.sky_depth_m (Cycles writes 1e10 m for the background), gets T = 1 and
// L_in = 0: the render's background already shows the sky (the world texture holds the
// atmosphere's whole path radiance), so Image x T + Inscatter leaves it as rendered.
// A NaN, negative or -infinite depth is an error naming the pixel.
//
// Frame: Blender's world, Z up, metres; the planet centre is straight below the scene
// origin (scene.hpp), so every point's altitude is its distance from the centre minus the
// ground radius, and a camera or a surface below the ground sphere sees the air of the
// ground (densities are clamped at altitude 0).
//
// Threads: TBB; results do not depend on the thread count. Cancellable through Progress.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/atmosphere/luts.hpp"
#include "welkin/atmosphere/observer.hpp"
#include "welkin/base/camera.hpp"
#include "welkin/base/progress.hpp"
#include "welkin/base/row_range.hpp"
#include "welkin/color/color_space.hpp"

namespace welkin {

struct AerialOptions {
    enum class Method { Froxel, Raymarch };
    Method method = Method::Froxel;
    // Froxel volume: screen-space columns and depth slices (Hillaire 2020: 32 x 32 x 32).
    int froxel_width = 32, froxel_height = 32, froxel_slices = 32;
    // Largest depth the volume covers, m; 0 fits it to the depth buffer's largest finite
    // (non-sky) depth.
    double max_depth_m = 0.0;
    // Sub-steps per depth slice when the volume is built.
    int steps_per_slice = 4;
    // Per-pixel ray march ("raymarch" method, and the reference the froxels are tested
    // against): steps along each pixel's ray up to its depth.
    int raymarch_steps = 64;
    // Depths at or beyond this (and +infinity) are sky pixels; Cycles writes 1e10 m for
    // the background.
    double sky_depth_m = 1e9;

    void validate(const std::string& parameter = "aerial") const;
};

const char* aerial_method_name(AerialOptions::Method method);
// "froxel" | "raymarch"; throws InvalidArgument naming `parameter`.
AerialOptions::Method aerial_method_from_name(const std::string& name,
                                              const std::string& parameter = "aerial.method");

// What aerial perspective needs of one frame: the air (the atmosphere, the sizes of its
// LUTs, the observer at the scene origin with the sun), the camera at its render
// resolution, and the exposure of the passes. SceneDescription::aerial_view() makes one.
struct AerialView {
    Atmosphere atmosphere;
    LutResolution luts;
    Observer origin;  // the scene origin's altitude above the ground and the sun
    Camera camera;
    int width = 0, height = 0;  // the render resolution the depth buffer must have
    double exposure = 1.0;
    AerialOptions options;
    ColorSpace color_space = ColorSpace::Rec709;  // of the RGB passes (color_space.hpp)

    // The planet centre in the world frame (straight below the scene origin).
    glm::dvec3 planet_centre() const { return {0.0, 0.0, -(atmosphere.bottom_radius_m + origin.altitude_m)}; }
    // Throws InvalidArgument naming the field.
    void validate() const;
};

struct AerialPasses {
    int width = 0, height = 0;
    std::vector<float> inscatter;      // (height, width, 3), top row first
    std::vector<float> transmittance;  // (height, width, 3), top row first
};

// What the aerial passes of one pixel take: its depth in and two RGB passes out, float.
// Callers add what they hold besides and ask base/memory.hpp's check_frame_memory first.
inline constexpr double kAerialPassBytesPerPixel = 7 * sizeof(float);

// Throws InvalidArgument naming "depth" (and the pixel) for a NaN, negative or -infinite
// value, or when depth.size() != width * height.
void validate_depth(std::span<const float> depth, int width, int height);

// The largest depth below sky_depth_m (0 when every pixel is sky).
double largest_finite_depth(std::span<const float> depth, double sky_depth_m);

// True for a sky pixel's depth.
inline bool is_sky_depth(float depth, double sky_depth_m) {
    return !(double(depth) < sky_depth_m);  // +inf, and beyond the threshold
}

// Hillaire's camera-frustum volume for one camera and sun.
class AerialPerspectiveVolume {
public:
    // `luts` must be built from view.atmosphere with view.luts. max_depth_m > 0.
    AerialPerspectiveVolume(const AerialView& view, const AtmosphereLuts& luts, int width, int height,
                            double max_depth_m, Progress* progress = nullptr);

    struct Sample {
        std::array<float, 3> inscatter, transmittance;
    };
    // Screen coordinates (sx, sy) in [0, 1], top-left origin (clamped); depth as the Z
    // pass, clamped to [0, max_depth_m()] (the caller decides what sky pixels get).
    Sample sample(double sx, double sy, double depth) const;

    int columns() const { return nx_; }
    int rows() const { return ny_; }
    int slices() const { return nz_; }
    double max_depth_m() const { return max_depth_; }
    // The depth of slice k in 1..slices().
    double slice_depth(int k) const;

private:
    int nx_, ny_, nz_;
    double max_depth_;
    // Per froxel (k - 1, j, i), RGB: inscatter (times exposure) and optical depth -ln T.
    std::vector<float> inscatter_, optical_depth_;
    std::size_t index(int i, int j, int k) const {
        return ((std::size_t(k) * std::size_t(ny_) + std::size_t(j)) * std::size_t(nx_) + std::size_t(i)) * 3;
    }
};

// One frame's passes prepared once and computed band by band (the render engine's tiles):
// the constructor does the frame-wide work (the checks of aerial_perspective(), the LUTs,
// the froxel depth range fitted to the whole depth buffer and the volume over the whole
// screen), render() the per-pixel part for a band of rows. A band's values are exactly
// those of aerial_perspective() in those rows, so bands of any size tile the whole frame
// exactly. `depth` is not copied: it must outlive the AerialFrame. `method`: the view's
// options.method unless given. render() may be called from several threads at once.
class AerialFrame {
public:
    AerialFrame(const AerialView& view, std::span<const float> depth, int width, int height,
                std::optional<AerialOptions::Method> method = std::nullopt);
    ~AerialFrame();
    AerialFrame(const AerialFrame&) = delete;
    AerialFrame& operator=(const AerialFrame&) = delete;

    // Rows [rows.begin, rows.end) into `inscatter` and `transmittance`, each
    // rows.size() x width x 3 (RGB, the band's top row first); sky pixels get T = 1,
    // L = 0. Throws InvalidArgument naming "rows" for a bad range or wrong sizes.
    void render(RowRange rows, std::span<float> inscatter, std::span<float> transmittance,
                Progress* progress = nullptr) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The passes for `depth` ((height, width), top row first, the Z pass), width x height
// being the scene's render resolution, by the scene's aerial.method. Throws
// InvalidArgument naming "camera" (none), "depth", "resolution" or "rows".
// `rows`: only those rows of the passes are computed (the others are left at T = 1,
// L = 0), with exactly the values of the whole frame's call: the froxel depth range is
// fitted to the whole depth buffer and the volume spans the whole screen either way.
AerialPasses aerial_perspective(const AerialView& view, std::span<const float> depth, int width, int height,
                                Progress* progress = nullptr, RowRange rows = {});

// Either way explicitly (tests and the bench compare them).
AerialPasses aerial_perspective_froxel(const AerialView& view, std::span<const float> depth, int width,
                                       int height, Progress* progress = nullptr, RowRange rows = {});
AerialPasses aerial_perspective_raymarch(const AerialView& view, std::span<const float> depth, int width,
                                         int height, Progress* progress = nullptr, RowRange rows = {});

// The air along explicit rays: the per-pixel march of "raymarch" (the same steps, the same
// colour) for rays that are not a camera's pixels, each ending at its own distance. This
// is the air in front of clouds, shared by the camera cloud passes (cloud_passes.hpp) and
// the equirect sky's clouds (sky_image.hpp), so that both apply exactly the same air.
// Ray i starts at origins[i] (origins[0] for all when there is one; world frame, the
// planet centre at `planet_centre`) along unit directions[i] and ends at distances[i] m;
// a distance that is not > 0 (or NaN) gives T = 1, L = 0 without marching. `luts`: of
// `atmosphere`. `steps`: per ray (aerial.raymarch_steps), >= 1.
struct AirAlongRays {
    // RGB as the passes': L_in times `exposure`, and the sunlit-surface T; (n, 3).
    std::vector<float> inscatter, transmittance;
    // With `spectral`: per atmosphere channel, (n, channels): L_in in W m^-2 sr^-1 nm^-1
    // (E_sun included, no exposure) and T; empty otherwise.
    std::vector<float> inscatter_spectral, transmittance_spectral;
};
AirAlongRays aerial_along_rays(const Atmosphere& atmosphere, const AtmosphereLuts& luts,
                               const glm::dvec3& planet_centre, const glm::dvec3& sun_direction,
                               std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                               std::span<const double> distances, int steps, double exposure,
                               bool spectral = false, ColorSpace color_space = ColorSpace::Rec709);

}  // namespace welkin
