//! Surface materials and how a LiDAR beam interacts with them.
//!
//! Every material answers three questions for a beam arriving at incidence
//! angle `θ` (between the beam and the surface normal):
//!
//! - **surface echo** `σ(θ)`: the part of the light scattered straight back
//!   to the sensor, in reflectivity units (a white Lambertian target at normal
//!   incidence is 1). Diffuse surfaces scatter `ρ cos θ`; glass, mirrors and
//!   other reflective surfaces add a sharp specular peak
//!   `p · exp(-(θ/θ₀)²)` that is strong only near normal incidence (the
//!   intensity peak of the paper's "Reflection Model of Different
//!   Materials") on top of a weak broad lobe `ρ cosⁿ θ` (dust, coating haze;
//!   `n = 1` is Lambertian, larger `n` makes glass vanish sooner at oblique
//!   incidence, as the paper describes).
//! - **specular reflectance** `R(θ)`: the fraction of the power continuing
//!   along the mirrored direction. Dielectrics (glass, coated panels) follow
//!   Schlick's approximation of the Fresnel equations,
//!   `R(θ) = R₀ + (1 - R₀)(1 - cos θ)⁵`, so glass turns into a mirror at
//!   grazing incidence; metal mirrors reflect `R₀` at every angle.
//! - **transmittance** `T(θ)`: the fraction passing straight through (glass
//!   only), `T₀ (1 - R(θ)) / (1 - R₀)`.
//!
//! Power factors apply twice (out and back), see [`super::echo`].

use serde::{Deserialize, Serialize};

/// The four material classes of 3DRef.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MaterialKind {
    /// Opaque, Lambertian (walls, floors, furniture).
    Diffuse,
    /// Transparent: surface echo, transmission and specular reflection.
    Glass,
    /// Opaque specular reflector with a weak surface echo.
    Mirror,
    /// Diffuse plus some specular reflection (whiteboard, monitor, polished
    /// metal).
    OtherReflective,
}

impl MaterialKind {
    /// The 3DRef label of a surface echo of this material reached directly:
    /// 1 normal, 2 glass, 3 mirror, 4 other reflective.
    pub fn label(self) -> u8 {
        match self {
            MaterialKind::Diffuse => 1,
            MaterialKind::Glass => 2,
            MaterialKind::Mirror => 3,
            MaterialKind::OtherReflective => 4,
        }
    }

    /// Name as written in scene files and `planes.json`.
    pub fn name(self) -> &'static str {
        match self {
            MaterialKind::Diffuse => "diffuse",
            MaterialKind::Glass => "glass",
            MaterialKind::Mirror => "mirror",
            MaterialKind::OtherReflective => "other-reflective",
        }
    }

    /// Whether the material is one of the reflective classes (glass, mirror,
    /// other reflective), i.e. a ground-truth reflective plane.
    pub fn is_reflective(self) -> bool {
        self != MaterialKind::Diffuse
    }
}

/// Optical parameters of a surface (validated; see the module docs for the
/// model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Class, which decides the label of the surface echo.
    pub kind: MaterialKind,
    /// Reflectivity `ρ` of the broad lobe of the surface echo (0..1).
    pub diffuse: f64,
    /// Exponent `n` of the broad lobe `ρ cosⁿ θ` (1: Lambertian).
    pub lobe: f64,
    /// Height `p` of the specular peak of the surface echo at normal
    /// incidence, reflectivity units (may exceed 1: the peak is focused).
    pub echo_peak: f64,
    /// Width `θ₀` of the specular peak, radians.
    pub echo_width: f64,
    /// Specular reflectance at normal incidence `R₀` (0..1).
    pub reflectance: f64,
    /// Transmittance at normal incidence `T₀` (0..1, glass only).
    pub transmittance: f64,
    /// Whether `R(θ)` follows Schlick's Fresnel approximation (dielectrics)
    /// or is constant (metal mirrors).
    pub fresnel: bool,
}

impl Material {
    /// A Lambertian surface of reflectivity `rho`.
    pub fn diffuse(rho: f64) -> Self {
        Self {
            kind: MaterialKind::Diffuse,
            diffuse: rho,
            lobe: 1.0,
            echo_peak: 0.0,
            echo_width: 1.0,
            reflectance: 0.0,
            transmittance: 0.0,
            fresnel: false,
        }
    }

    /// Surface echo `σ(θ)` for `cos θ = cos_theta` (reflectivity units).
    ///
    /// Monotone non-increasing in `θ` for every material.
    #[inline]
    pub fn surface_echo(&self, cos_theta: f64) -> f64 {
        let c = cos_theta.clamp(0.0, 1.0);
        let mut s = if self.lobe == 1.0 {
            self.diffuse * c
        } else {
            self.diffuse * c.powf(self.lobe)
        };
        if self.echo_peak > 0.0 {
            let theta = c.acos();
            let x = theta / self.echo_width;
            s += self.echo_peak * (-x * x).exp();
        }
        s
    }

    /// Specular reflectance `R(θ)`.
    #[inline]
    pub fn reflectance(&self, cos_theta: f64) -> f64 {
        if self.reflectance <= 0.0 {
            return 0.0;
        }
        if self.fresnel {
            let m = 1.0 - cos_theta.clamp(0.0, 1.0);
            let m2 = m * m;
            self.reflectance + (1.0 - self.reflectance) * m2 * m2 * m
        } else {
            self.reflectance
        }
    }

    /// Transmittance `T(θ)` (0 for opaque materials).
    #[inline]
    pub fn transmittance(&self, cos_theta: f64) -> f64 {
        if self.transmittance <= 0.0 {
            return 0.0;
        }
        let r0 = self.reflectance.min(0.999);
        self.transmittance * (1.0 - self.reflectance(cos_theta)).max(0.0) / (1.0 - r0)
    }

    /// Largest surface echo this material can produce (at normal incidence),
    /// used to prune rays that can no longer be detected.
    pub fn max_echo(&self) -> f64 {
        self.diffuse + self.echo_peak
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glass() -> Material {
        Material {
            kind: MaterialKind::Glass,
            diffuse: 0.03,
            lobe: 8.0,
            echo_peak: 1.0,
            echo_width: 4f64.to_radians(),
            reflectance: 0.1,
            transmittance: 0.8,
            fresnel: true,
        }
    }

    #[test]
    fn glass_echo_peaks_at_normal_incidence_and_falls_fast() {
        let g = glass();
        let mut last = f64::INFINITY;
        for deg in 0..90 {
            let s = g.surface_echo((deg as f64).to_radians().cos());
            assert!(s <= last, "not monotone at {deg} deg");
            last = s;
        }
        let at0 = g.surface_echo(1.0);
        let at10 = g.surface_echo(10f64.to_radians().cos());
        assert!(at10 < 0.1 * at0, "{at10} vs {at0}");
    }

    #[test]
    fn fresnel_reflectance_grows_towards_grazing_and_energy_is_conserved() {
        let g = glass();
        assert!((g.reflectance(1.0) - 0.1).abs() < 1e-12);
        assert!((g.transmittance(1.0) - 0.8).abs() < 1e-12);
        let mut last = 0.0;
        for deg in 0..=90 {
            let c = (deg as f64).to_radians().cos();
            let r = g.reflectance(c);
            assert!(r >= last);
            assert!(r + g.transmittance(c) <= 1.0 + 1e-12);
            last = r;
        }
        assert!(g.reflectance(0.0) > 0.99);
    }

    #[test]
    fn diffuse_is_lambertian() {
        let d = Material::diffuse(0.5);
        assert!((d.surface_echo(0.5) - 0.25).abs() < 1e-12);
        assert_eq!(d.reflectance(0.3), 0.0);
        assert_eq!(d.transmittance(0.3), 0.0);
    }
}
