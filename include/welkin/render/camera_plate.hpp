// SPDX-License-Identifier: Apache-2.0
// A camera plate: what the scene camera sees of the sky, the sun and the air over the
// ground, with no meshes (the Welkin render engine's frame, `welkin plate`).
//
// For every pixel of the scene's render (scene.resolution, camera.hpp's rays):
//   * A ray that misses the ground sphere (the planet, radius atmosphere.bottom_radius_m,
//     centred below the scene origin: scene.hpp) sees the sky: the sky method's path
//     radiance for its direction (sky/method.hpp, one call for all sky pixels, the observer
//     at the camera's altitude), plus the sun's disc.
//   * A ray that hits it sees the ground through the air: its depth (Blender's Z
//     convention, camera.hpp) goes to aerial_perspective() and the pixel is
//     T x L_ground + L_in (the compositor's Image x T + Inscatter), with L_ground the lit
//     ground of ground.hpp, albedo / pi x E(p) at the hit point p (scene.ground; the
//     atmosphere's ground_albedo unless scene.ground_albedo is set; converted to RGB as
//     sunlight), or 0 when scene.ground is off (a black ground).
// Passes (linear Rec.709, W m^-2 sr^-1, times the scene's exposure; top row first):
//   combined       = sky (sky pixels), transmittance x L_ground + inscatter (ground pixels)
//   sky            = sky radiance with the disc on sky pixels, 0 on ground pixels
//   inscatter      = Welkin.AerialInscatter (0 on sky pixels)
//   transmittance  = Welkin.AerialTransmittance (1 on sky pixels)
//   depth          = the Z pass: depth to the ground, +infinity on sky pixels
//   clouds         = Welkin.Clouds (premultiplied RGBA, the air in front included) of the
//                    scene's clouds (cloud_passes.hpp), the ground hiding what lies below it;
//                    alpha 0 everywhere without clouds
//   cloud_depth    = Welkin.CloudDepth (Z convention; 1e10 where no cloud)
// With clouds, combined = Clouds.rgb + (1 - Clouds.a) x (the clear combined above): the
// compositor's formula of cloud_passes.hpp with Image = sky (T = 1) or the black ground;
// the sun's disc is dimmed by the cloud's transmittance 1 - alpha.
//
// Frame approximation: the sky method's observer stands at the camera's altitude with the
// world's Z as its zenith; the true zenith at a camera d metres from the scene origin's
// vertical tilts by d / R (1e-3 rad at 6.4 km). Orthographic rays start at different
// points but all see the sky from the camera's altitude.
//
// The sun's disc: E_sun T / Omega_sun x limb darkening (sun.hpp) at every sample whose
// ray is within the disc and above the horizon. Pixels whose centre ray lies within the
// disc's radius plus two pixel footprints are supersampled on an S x S grid, S chosen so
// that the sample spacing is at most 1/8 of the disc's radius (2 <= S <= 64), so a disc
// smaller than a pixel is antialiased and its energy is kept to the sampling error.
//
// Rows (the render engine's tiles, the viewport preview's bands): CameraPlateRenderer
// prepares the frame once (the checks, the cloud density, the depth of the whole frame:
// one ray-sphere test per pixel, the sky method chosen for the whole frame's sky pixels,
// the sun's radiometry and the aerial perspective's LUTs, fitted depth range and froxel
// volume: AerialFrame) and then renders any band of rows [rows.begin, rows.end) with the
// values the whole frame has in those rows (height = rows.size(), row_begin = rows.begin):
// the sky, the disc, the aerial and cloud passes of the band's pixels only. So bands tile
// the frame exactly and a band costs its share of the frame (plus the sky method's
// per-call set-up: the lut method's sky-view LUT, a few ms). render_camera_plate() is one
// CameraPlateRenderer's render().
//
// Errors (InvalidArgument): no camera ("camera"), a camera below the ground
// ("camera.matrix_world"), a bad row range ("rows"), a cloud volume that cannot be read
// ("clouds.volumes[i].file", before any work), and whatever the scene's validation or the
// sky method refuse. Cancelled when `progress` cancels.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "welkin/base/progress.hpp"
#include "welkin/base/row_range.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin {

struct CameraPlate {
    int width = 0, height = 0;                                   // of the arrays: the band's rows
    int row_begin = 0;                                           // the band's first row in the frame
    int frame_height = 0;                                        // the whole frame's
    std::vector<float> combined, sky, inscatter, transmittance;  // (height, width, 3)
    std::vector<float> depth;                                    // (height, width)
    std::vector<float> clouds;                                   // (height, width, 4)
    std::vector<float> cloud_depth;                              // (height, width)
    std::string method;  // the sky method that ran (auto resolved by the method itself)
};

CameraPlate render_camera_plate(const SceneDescription& scene, Progress* progress = nullptr,
                                RowRange rows = {});

// A frame prepared for rendering band by band (above). The constructor throws what
// render_camera_plate() throws for the scene; render() throws InvalidArgument naming
// "rows" for a bad range, and Cancelled when `progress` cancels. render() may be called
// from several threads at once (each call has its own buffers).
class CameraPlateRenderer {
public:
    explicit CameraPlateRenderer(const SceneDescription& scene);
    ~CameraPlateRenderer();
    CameraPlateRenderer(const CameraPlateRenderer&) = delete;
    CameraPlateRenderer& operator=(const CameraPlateRenderer&) = delete;

    CameraPlate render(RowRange rows = {}, Progress* progress = nullptr) const;

    int width() const;
    int height() const;
    const std::string& method() const;  // the sky method the bands render with
    bool has_clouds() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace welkin
