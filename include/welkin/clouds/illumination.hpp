// SPDX-License-Identifier: Apache-2.0
// What lights a cloud: the sun's irradiance at a point, after the atmosphere, and the
// sky radiance around it, uniform over each hemisphere about the local zenith. Both cloud integrators (the
// fast march and the path tracer) use the same illumination, so the reference tests the lighting
// approximation alone, not a different light.
//
// From the atmosphere (AtmosphereIllumination), at a point p at radius r = |p - centre|
// with the sun at zenith cosine mu_s there, per channel:
//   sun:  E_sun T(r, mu_s) times the visible fraction of the disc (TransmittanceLut::to_sun,
//         Bruneton 2017's GetTransmittanceToSun): the sun's colour at the cloud's altitude;
//   sky:  E_sun L_above(r, mu_s) and E_sun L_below(r, mu_s), the multiple-scattering
//         LUT's means of the light arriving at p (all orders of air scattering and the
//         ground's reflection, in Hillaire 2020's model) over the upper and the lower
//         hemisphere ("The sky's two hemispheres" in multiscattering_lut.hpp); their mean
//         is Psi_ms. A cloud lit by them is lit by a sky of one radiance above its
//         horizon and another below (the sky's azimuthal structure and its structure in
//         zenith angle within a hemisphere are left out). The split matters: seen from
//         2 km up the lower half is 0.5 to 2.8 times the upper, from 9 km 1.6 to 6.8 times
//         (docs/validation.md, "The light from below").
// Units: W m^-2 nm^-1 (irradiance, normal incidence) and W m^-2 sr^-1 nm^-1.
// The air between the cloud and the camera (aerial perspective) is not part of this.
#pragma once

#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/atmosphere/luts.hpp"
#include "welkin/atmosphere/observer.hpp"

namespace welkin {

class CloudIllumination {
public:
    virtual ~CloudIllumination() = default;
    virtual std::size_t channels() const = 0;
    virtual glm::dvec3 sun_direction() const = 0;                            // unit, towards the sun
    virtual glm::dvec3 zenith(const glm::dvec3& p) const = 0;                // unit, the local vertical at p
    virtual void sun_irradiance(const glm::dvec3& p, float* out) const = 0;  // channels() values
    // The mean sky radiance over the hemisphere above p's horizon and the one below it
    // (channels() values each).
    virtual void sky_radiance(const glm::dvec3& p, float* above, float* below) const = 0;
    // Whether above equals below everywhere (a uniform sky: a cloud's depth does not matter).
    virtual bool uniform_sky() const { return false; }
};

// The same light everywhere (tests, and scenes lit without an atmosphere).
class ConstantIllumination final : public CloudIllumination {
public:
    // sun_direction normalised here; InvalidArgument if it is not a finite non-zero vector
    // or the spectra differ in length / hold negative or non-finite values (the error names
    // the parameter). The sky is ambient_radiance all round, or ambient_radiance above the
    // horizon and ground_radiance below.
    ConstantIllumination(const glm::dvec3& sun_direction, std::vector<float> sun_irradiance,
                         std::vector<float> ambient_radiance);
    ConstantIllumination(const glm::dvec3& sun_direction, std::vector<float> sun_irradiance,
                         std::vector<float> ambient_radiance, std::vector<float> ground_radiance);
    std::size_t channels() const override { return sun_.size(); }
    glm::dvec3 sun_direction() const override { return s_; }
    glm::dvec3 zenith(const glm::dvec3&) const override { return {0.0, 0.0, 1.0}; }
    void sun_irradiance(const glm::dvec3&, float* out) const override;
    void sky_radiance(const glm::dvec3&, float* above, float* below) const override;
    bool uniform_sky() const override { return above_ == below_; }

private:
    glm::dvec3 s_;
    std::vector<float> sun_, above_, below_;
};

// Sun and sky from the atmosphere's LUTs; the world origin stands observer.altitude_m above
// the ground (the planet centre straight below it).
class AtmosphereIllumination final : public CloudIllumination {
public:
    AtmosphereIllumination(const Atmosphere& atmosphere, const Observer& observer,
                           const LutResolution& resolution = {});
    std::size_t channels() const override { return luts_->channels(); }
    glm::dvec3 sun_direction() const override { return s_; }
    glm::dvec3 zenith(const glm::dvec3& p) const override;
    void sun_irradiance(const glm::dvec3& p, float* out) const override;
    void sky_radiance(const glm::dvec3& p, float* above, float* below) const override;
    // Its atmosphere's LUTs (for the air in front of the clouds, aerial_along_rays).
    const AtmosphereLuts& luts() const { return *luts_; }

private:
    std::shared_ptr<const AtmosphereLuts> luts_;
    glm::dvec3 s_, centre_;
};

}  // namespace welkin
