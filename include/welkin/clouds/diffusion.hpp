// SPDX-License-Identifier: Apache-2.0
// Multiple scattering in thick clouds: the delta-Eddington slab along the sun line.
//
// Why. Wrenninge's octaves (clouds/lighting.hpp) attenuate every order as exp(-a^i tau_sun):
// deep in a thick cloud they all vanish, but the light there does not. In a thick, nearly
// conservative medium the diffuse light falls off only linearly with optical depth: the
// net flux F is constant and Fick's law F = -(1/3) dphi/dtau' holds, so the fluence phi is
// a straight line in the transport-scaled optical depth tau' (diffusion theory; e.g.
// Bohren & Clothiaux 2006, "Fundamentals of Atmospheric Radiation", ch. 5-6). The octaves
// leave the dense cumulus base 49 % too dark (bench/clouds).
//
// The model. A sample x of a view ray sees along the sun's line through it the cloud's
// optical depth tau_sun towards the sun and tau_anti away from it. We treat the cloud as
// the plane-parallel slab normal to the sun that has those depths (the same 1D picture as
// the octaves' optical size), lit by the sun's irradiance E at normal incidence, and solve
// it in three parts that add up to the whole radiance field, without overlap:
//
//  1. Unscattered sunlight, E exp(-tau_sun): single scattering, exact (the march).
//  2. The similarity transformation (van de Hulst 1980, "Multiple light scattering", vol.
//     2, sec. 14; Joseph, Wiscombe & Weinman 1976, "The delta-Eddington approximation",
//     J. Atmos. Sci. 33) splits the phase into a forward delta of weight f and the rest:
//     light scattered into the forward peak keeps travelling along the beam. With f = g
//     (the phase's mean cosine, clamped to >= 0) the rest is isotropic and the scaled
//     medium has
//         tau' = (1 - albedo f) tau,   albedo' = (1 - f) albedo / (1 - albedo f),   g' = 0.
//     The scaled beam E exp(-tau') holds the unscattered light and the forward-scattered
//     light, so the forward-scattered part alone is E (exp(-tau'_sun) - exp(-tau_sun)).
//     It is nearly collimated, but it has scattered: its in-scattering into the view has
//     the angular distribution of twice-scattered light, the phase convolved with itself
//     (CloudPhase::twice: the Legendre moments multiply, so HG(g1) * HG(g2) = HG(g1 g2)).
//  3. The diffuse field of the scaled medium. We do not know how the cloud's surface is
//     oriented at x, so the slab is taken inclined to the sun at every angle, mu0 the
//     cosine between its normal n and the beam, its normal thickness Z = mu0 T' (T' the
//     scaled chord tau'_sun + tau'_anti along the sun line), x at normal depth z = mu0 t',
//     t' = tau'_sun; and the result is averaged over mu0 with the weight 2 mu0 dmu0: the
//     distribution of the surface's inclination where a parallel beam meets a convex body
//     (the share of its projected area). At normal incidence alone the slab gives light
//     too deep (its Eddington escape factor 1/2 + 3 mu0 / 4 is 1.25 at mu0 = 1; averaged
//     with 2 mu0 dmu0 it is 1, the normalisation of the escape function). For each mu0,
//     Eddington's approximation I = I0 + mu I1 (fluence phi = 4 pi I0, net flux along n
//     F = 4 pi I1 / 3) obeys, with the scaled beam e^{-z/mu0} (per unit irradiance E
//     normal to the sun) as source and an isotropic scaled phase,
//         dF/dz   = -(1 - albedo') phi + albedo' E e^{-z/mu0},
//         dphi/dz = -3 F,
//     so phi'' - k^2 phi = -3 albedo' E e^{-z/mu0}, k^2 = 3 (1 - albedo') (the inverse
//     diffusion length, per unit scaled depth). No diffuse light enters either face
//     (Marshak's conditions for Eddington's I: the inward hemispheric flux
//     phi/4 -+ F/2 = 0), i.e. phi(0) - (2/3) phi'(0) = 0 and phi(Z) + (2/3) phi'(Z) = 0:
//     the extrapolated boundary z0 = 2/3. Solution (eddington_slab below):
//         phi = A e^{-k z} + B e^{-k (Z - z)} + C e^{-z/mu0},  C = 3 albedo' mu0^2 E / (k^2 mu0^2 - 1),
//     and for albedo' = 1: phi = A + B z - 3 mu0^2 E e^{-z/mu0}; at mu0 = 1
//         B = -E (5 - e^{-Z}) / (Z + 4/3),   A = 5 E + (2/3) B,
//     so the transmitted flux (diffuse + direct) is (5/3) E / (Z + 4/3) and the reflected
//     one the rest: R + T = mu0 E exactly for every mu0 (tests/cpp/test_cloud_diffusion.cpp).
//     Deep in a thick slab phi = 3 F (Z + 2/3 - z): linear, as diffusion theory has it.
//     In-scattering of I = (phi + 3 F n.w)/(4 pi) with the real phase (whose first Legendre
//     moment is g: int p(w.w') (w'.n) dw' = g (w.n)) gives towards the viewer, averaged over
//     the slab's azimuth about the sun line (the mean of n is mu0 times the beam's direction),
//         J_diffuse = sigma_s (phi + 3 g F mu0 nu) / (4 pi),   nu = d . s,
//     clamped at 0 (at the faces phi = 2 |F|, so the clamp acts only for g beyond 2/3).
//     The mu0 average is a 3-point Gauss-Legendre rule in mu0^2.
//
// The source of sun light per unit sigma_s E at x is then
//     exp(-tau_sun) p(nu) + (exp(-tau'_sun) - exp(-tau_sun)) p2(nu) + (phi + 3 g F nu)/(4 pi E).
// Limits: in an optically thin cloud parts 2 and 3 are O(tau) of part 1, as second-order
// scattering is; in a thick conservative one part 3 is the linear diffusion profile and
// does not vanish at depth.
//
// The sides. The slab above is infinite across the sun line, so light that would leave a
// small, round cloud sideways stays in it: such a cloud came out a third too bright on its
// shadow side. Across the sun line the cloud has, along one transverse axis u (the
// horizontal normal to the sun, the one the march measures), a scaled optical chord W'
// through x. Diffusion in a body finite along u separates into transverse modes
// cos(n pi w / W_e) between the extrapolated boundaries (W_e = W' + 4/3, the same Marshak
// extrapolation of 2/3 at each side); mode n obeys the slab equation with the extra
// "buckling" B_n^2 = (n pi / W_e)^2 added to k^2: light lost through the sides acts as an
// absorption (the fundamental-mode treatment of reactor theory; e.g. Duderstadt &
// Hamilton 1976, "Nuclear Reactor Analysis", ch. 5). The fundamental mode, B = pi / W_e,
// is what remains deep in the cloud; the higher modes (n >= 3) decay within about
// 1 / (3 B) of the lit face, where the slab without leak holds. So
//     phi = phi_B + (phi_0 - phi_B) exp(-3 B t'),
// phi_B the slab with k^2 + B^2, phi_0 without, t' the scaled depth from the lit face;
// each inclination of the orientation average the same way. The other transverse axis is
// left infinite, as before: the march measures one chord, and a cloud wider than it leaks
// less, not more. W' infinite (no cloud across) is the slab itself. The leak and the blend
// follow from the mode expansion; nothing is fitted. What it buys is measured in
// docs/validation.md ("Under the add-on's own lighting"). Not modelled: the sky's share of
// multiple scattering (its own term, clouds/lighting.hpp).
#pragma once

namespace welkin {

// The diffuse field of Eddington's slab above, per unit irradiance normal to the beam: at
// scaled optical depth z in [0, Z] from the lit face of a slab of scaled optical thickness
// Z, lit at the cosine mu0 in (0, 1] from its normal, with scaled single-scattering albedo
// `albedo` in [0, 1] and an isotropic scaled phase.
struct DiffuseField {
    double fluence = 0.0;  // phi / E
    double flux = 0.0;     // F / E along the slab's normal, positive into the slab
};
// leak: the transverse buckling B^2 added to k^2 (the sides, above); 0 for the slab.
DiffuseField eddington_slab(double Z, double z, double albedo, double mu0 = 1.0, double leak = 0.0);

// The similarity-scaled medium of a cloud's albedo and phase mean cosine g (part 2 above).
struct SimilarityScaling {
    double forward = 0.0;      // f = max(g, 0)
    double depth_scale = 1.0;  // tau' / tau = 1 - albedo f
    double albedo = 1.0;       // albedo'
    SimilarityScaling(double albedo, double mean_cosine);
};

// The source of sun light above per unit sigma_s E (parts 1, 2 and 3), for the sun-line
// depths tau_sun, tau_anti (unscaled), the chord tau_side across the sun line (unscaled;
// infinity: no sides), nu = d . s, g the phase's mean cosine, p the phase and p2 the
// twice-scattered phase at nu.
double sun_source(const SimilarityScaling& sim, double tau_sun, double tau_anti, double tau_side, double nu,
                  double g, double p, double p2);

}  // namespace welkin
