// SPDX-License-Identifier: Apache-2.0
// One interface for every way of computing sky radiance.
//
// Every method answers the same question: the in-scattered (path) radiance reaching an
// observer from a set of view directions, given the atmosphere, the observer's altitude
// and the sun direction. "Sky radiance only": no sun disc, no light reflected by the
// ground surface at the end of the ray (light the ground reflects back into the air and
// that the air then scatters towards the observer is included where the method models
// multiple scattering). Rays that hit the ground carry the path radiance up to the ground.
//
// The ladder, from fast to exact (see docs/design.md):
//   analytic  no marching: plane-parallel single scattering with Chapman air masses
//   lut       Hillaire 2020: transmittance, multiple-scattering and sky-view LUTs
//   raymarch  nested single-scattering march plus Hillaire's multiple-scattering term
//   reference Monte-Carlo path tracing, all orders, ground reflection, seeded
// and "auto", which picks the cheapest of the first three that the chart shows meets a
// tolerance for the scene (sky/auto.hpp).
//
// Frame: Blender's world frame, Z up. The observer stands on the Z axis at
// bottom_radius + altitude from the planet centre. Output: radiance in
// W m^-2 sr^-1 nm^-1 for each of the atmosphere's wavelengths, row-major (N, C).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/luts.hpp"
#include "welkin/atmosphere/observer.hpp"
#include "welkin/base/progress.hpp"

namespace welkin {

// Options shared by all methods; each uses the ones that concern it.
struct SkyOptions {
    // lut: texture sizes (Hillaire 2020's defaults). The first three are the atmosphere's
    // LUTs (luts()); the sky-view LUT is built per view.
    int transmittance_width = 256, transmittance_height = 64;
    int multiscattering_size = 32;
    int skyview_width = 192, skyview_height = 108;
    // raymarch: steps along the view ray and along each ray towards the sun.
    int raymarch_steps = 64;
    int raymarch_sun_steps = 32;
    // reference: Monte-Carlo paths per direction (per wavelength) and the seed.
    int reference_paths = 4096;
    std::uint64_t seed = 1;
    // auto: the relative luminance error to meet (95th percentile over the sphere, against
    // the reference; see sky/auto.hpp), in [0.001, 10].
    // The default 0.1: the default lut meets it on the bruneton2017 preset at every charted
    // altitude with the sun 3 degrees or more up (bench/results/scenes.csv); under haze and
    // in twilight no fast method does, and auto falls back (sky/auto.hpp).
    double tolerance = 0.1;

    LutResolution luts() const { return {transmittance_width, transmittance_height, multiscattering_size}; }
    void validate() const;
};

// Per-direction standard error, filled by methods that estimate (reference); zero for
// deterministic ones.
struct SkyResult {
    std::vector<float> radiance;        // (N, C)
    std::vector<float> standard_error;  // (N, C), or empty
    std::size_t channels = 0;
};

class SkyMethod {
public:
    virtual ~SkyMethod() = default;
    virtual std::string name() const = 0;

    // Radiance for `directions` (unit vectors; zero-length or non-finite ones throw
    // InvalidArgument naming view_directions[i]). Writes (N, C) into out, which must hold
    // directions.size() * atmosphere.channels() floats. `standard_error`, if non-empty,
    // receives the per-value standard error (zeros for deterministic methods).
    virtual void radiance(const Atmosphere& atmosphere, const Observer& observer,
                          std::span<const glm::dvec3> directions, std::span<float> out,
                          std::span<float> standard_error = {}, Progress* progress = nullptr) const = 0;
};

// "analytic" | "lut" | "raymarch" | "reference" | "auto"; throws InvalidArgument otherwise.
std::unique_ptr<SkyMethod> make_sky_method(const std::string& name, const SkyOptions& options = {});
std::vector<std::string> sky_method_names();

// Convenience: allocate and run.
SkyResult sky_radiance(const SkyMethod& method, const Atmosphere& atmosphere, const Observer& observer,
                       std::span<const glm::dvec3> directions, Progress* progress = nullptr);

// The checks every deterministic method makes on entry: the atmosphere, the observer
// (returned validated), the directions, and the size of `out`; zero-fills standard_error.
Observer validate_deterministic_call(const Atmosphere& atmosphere, const Observer& observer,
                                     std::span<const glm::dvec3> directions, std::span<float> out,
                                     std::span<float> standard_error);

}  // namespace welkin
