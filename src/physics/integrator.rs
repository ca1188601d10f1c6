//! The time integrator of a dynamic step, written as the inertia terms of the static system
//! K D = F (rock-mass reference §4).
//!
//! Shi's step (3.2), D = v0 Δt + ½ a Δt² with v1 = 2D/Δt − v0, is Newmark with β = ½, γ = 1
//! (§4.1). It damps the middle band strongly (ξ ≈ ωΔt/4) but leaves modes with ωΔt ≫ 4 ringing
//! at period 2 with a spectral radius → 1: stiff contact springs and fixed-point springs then
//! alternate their forces for as long as a run lasts.
//!
//! dda3d keeps γ = 1 and raises β from ½ to at most 9/16. The velocity update v1 = v0 + Δt a1
//! stays Shi's (it does not carry the last step's acceleration), slow modes keep Shi's damping,
//! and modes far too stiff for Δt shrink by ρ∞ per step, with
//! β = (1 + 3ρ∞) / (2 (1 + ρ∞)²): ρ∞ = 1 is Shi's step, ρ∞ = ⅓ (β = 9/16) the double root
//! −⅓ of the optimal dissipative Newmark (§4.2).
//!
//! Why not generalized-α or HHT (§4.2–4.3), which damp slow modes less? Both weight the last
//! step's static residual into the next (α_f r0), and Newmark with γ < 1 carries (1 − γ) a0
//! into the velocity: across a contact that opens or closes, the previous step's contact force
//! acts once more. Measured with these schemes (all exact on linear systems, see the tests):
//! the paper's stable block (`scenes/slope_stable.toml`, dynamic, 10 s) was thrown 214 m by
//! generalized-α ρ∞ = 0.8 (ALM) and crept 0.24 m under HHT ρ∞ = 0.8 (penalty); Newmark
//! γ = 0.5625 (ρ∞ = 0.6) gave the rockfall 1 MJ it never had. With γ = 1 none of these appear.

use super::mechanics::{Mat12, Vec12};

/// One member of the Newmark family (Shi's step: β = ½, γ = 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scheme {
    pub beta: f64,
    pub gamma: f64,
}

/// What a block carries between dynamic steps, in its 12-DOF basis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    pub velocity: Vec12,
    pub acceleration: Vec12,
}

impl Scheme {
    /// Shi's step (3.2).
    pub const SHI: Scheme = Scheme {
        beta: 0.5,
        gamma: 1.0,
    };

    /// The smallest ρ∞ of the family with γ = 1.
    pub const MIN_SPECTRAL_RADIUS: f64 = 1.0 / 3.0;

    /// γ = 1 and β = (1 + 3ρ∞) / (2 (1 + ρ∞)²), for ρ∞ ∈ [⅓, 1]: the larger root of the
    /// amplification of a mode with ωΔt → ∞ is −ρ∞ (derivation in the module's tests).
    pub fn with_spectral_radius(rho_inf: f64) -> Scheme {
        let r = rho_inf.clamp(Self::MIN_SPECTRAL_RADIUS, 1.0);
        if r == 1.0 {
            return Scheme::SHI;
        }
        Scheme {
            beta: (1.0 + 3.0 * r) / (2.0 * (1.0 + r) * (1.0 + r)),
            gamma: 1.0,
        }
    }

    pub fn is_shi(&self) -> bool {
        *self == Scheme::SHI
    }

    /// The multiple of M added to K_ii: 1/(β Δt²), 2/Δt² for Shi (R4.3 with α_m = α_f = 0).
    pub fn mass_factor(&self, dt: f64) -> f64 {
        if self.is_shi() {
            // Written as in (3.2), so that Shi's runs keep their bits.
            2.0 / (dt * dt)
        } else {
            1.0 / (self.beta * dt * dt)
        }
    }

    /// The inertia terms added to F_i: M [v0/(β Δt) + (1/(2β) − 1) a0], 2 M v0 / Δt for Shi.
    pub fn inertia_load(&self, m: &Mat12, k: &Kinematics, dt: f64) -> Vec12 {
        if self.is_shi() {
            return m * k.velocity * (2.0 / dt);
        }
        let b = self.beta;
        m * (k.velocity / (b * dt) + k.acceleration * (0.5 / b - 1.0))
    }

    /// The state after a converged step of length `dt` with solution `d` (R4.4):
    /// a1 = (D − Δt v0 − Δt² (½ − β) a0) / (β Δt²), v1 = v0 + Δt [(1 − γ) a0 + γ a1].
    pub fn advance(&self, k: &Kinematics, d: &Vec12, dt: f64) -> Kinematics {
        if self.is_shi() {
            // (3.2): v1 = 2D/Δt − v0.
            let velocity = d * (2.0 / dt) - k.velocity;
            return Kinematics {
                acceleration: (velocity - k.velocity) / dt,
                velocity,
            };
        }
        let (b, g) = (self.beta, self.gamma);
        let a1 = (d - k.velocity * dt - k.acceleration * (dt * dt * (0.5 - b))) / (b * dt * dt);
        Kinematics {
            velocity: k.velocity + (k.acceleration * (1.0 - g) + a1 * g) * dt,
            acceleration: a1,
        }
    }
}

impl Kinematics {
    pub fn at_rest() -> Kinematics {
        Kinematics {
            velocity: Vec12::zeros(),
            acceleration: Vec12::zeros(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    /// One step of the oscillator ẍ + ω²x = f (unit mass) through the DDA form:
    /// (mass factor + ω²) D = inertia load + f − ω² x0.
    fn step1(s: &Scheme, omega: f64, x: f64, k: &Kinematics, f: f64, dt: f64) -> (f64, Kinematics) {
        let m = Mat12::identity();
        let load = s.inertia_load(&m, k, dt)[0] + f - omega * omega * x;
        let mut d = Vec12::zeros();
        d[0] = load / (s.mass_factor(dt) + omega * omega);
        (x + d[0], s.advance(k, &d, dt))
    }

    fn state(v: f64, a: f64) -> Kinematics {
        let mut k = Kinematics::at_rest();
        k.velocity[0] = v;
        k.acceleration[0] = a;
        k
    }

    /// The spectral radius of one step (Δt = 1) of ẍ + Ω²x = 0, from the amplification matrix
    /// on (x, v, a) built column by column through the DDA form.
    fn spectral_radius(s: &Scheme, omega: f64) -> f64 {
        let mut cols = Matrix3::zeros();
        for j in 0..3 {
            let mut e = [0.0; 3];
            e[j] = 1.0;
            let (x1, k1) = step1(s, omega, e[0], &state(e[1], e[2]), 0.0, 1.0);
            cols[(0, j)] = x1;
            cols[(1, j)] = k1.velocity[0];
            cols[(2, j)] = k1.acceleration[0];
        }
        cols.complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max)
    }

    /// Free oscillator ẍ = −ω² x from x = 0, v = 1: (x, v) after `n` steps.
    fn oscillate(s: &Scheme, omega: f64, dt: f64, n: usize) -> (f64, f64) {
        let (mut x, mut k) = (0.0, state(1.0, 0.0));
        for _ in 0..n {
            (x, k) = step1(s, omega, x, &k, 0.0, dt);
        }
        (x, k.velocity[0])
    }

    #[test]
    fn the_spectral_radius_at_infinity_is_the_parameter() {
        for r in [1.0 / 3.0, 0.4, 0.5, 0.65, 0.8, 0.95, 1.0] {
            let s = Scheme::with_spectral_radius(r);
            assert_eq!(s.gamma, 1.0);
            let far = spectral_radius(&s, 1e6);
            assert!((far - r).abs() < 1e-4, "ρ∞ {r}: {far}");
            // Unconditionally stable: no mode grows, whatever ωΔt.
            for k in 0..60 {
                let omega = 10f64.powf(-2.0 + 0.1 * k as f64);
                let rho = spectral_radius(&s, omega);
                assert!(rho <= 1.0 + 1e-9, "ρ∞ {r}, Ω {omega}: {rho}");
            }
        }
        // Shi's closed forms (§4.1): ρ = (1 + Ω²/2)^(-1/2) below Ω = 4, ⅓ at Ω = 4.
        for omega in [0.5, 1.0, 3.0] {
            let want = (1.0_f64 + 0.5 * omega * omega).powf(-0.5);
            assert!((spectral_radius(&Scheme::SHI, omega) - want).abs() < 1e-9);
        }
        assert!((spectral_radius(&Scheme::SHI, 4.0) - 1.0 / 3.0).abs() < 1e-6);
        // ⅓ is the double root of the optimal dissipative Newmark γ = 1, β = 9/16 (§4.2).
        assert!((Scheme::with_spectral_radius(1.0 / 3.0).beta - 9.0 / 16.0).abs() < 1e-15);
    }

    #[test]
    fn rho_one_is_shis_literal_step() {
        assert!(Scheme::with_spectral_radius(1.0).is_shi());
        // The general formulas with Shi's constants reproduce (3.2) to rounding.
        let general = Scheme {
            gamma: 1.0 + 4.0 * f64::EPSILON,
            ..Scheme::SHI
        };
        assert!(!general.is_shi());
        let (mut xs, mut ks) = (0.3, state(1.0, 0.0));
        let (mut xg, mut kg) = (0.3, state(1.0, -2.0));
        for _ in 0..200 {
            (xs, ks) = step1(&Scheme::SHI, 3.0, xs, &ks, 0.5, 0.01);
            (xg, kg) = step1(&general, 3.0, xg, &kg, 0.5, 0.01);
        }
        assert!((xs - xg).abs() < 1e-12, "{xs} {xg}");
        assert!((ks.velocity[0] - kg.velocity[0]).abs() < 1e-10);
    }

    #[test]
    fn stiff_modes_are_damped_and_slow_modes_keep_shis_damping() {
        // §4.3: a stiff mode at Ω = 184 kicked with v = 1: its velocity after 40 steps.
        let (_, shi) = oscillate(&Scheme::SHI, 184.0, 1.0, 40);
        assert!(shi.abs() > 0.98, "{shi}");
        for r in [1.0 / 3.0, 0.5, 0.8] {
            let (_, v) = oscillate(&Scheme::with_spectral_radius(r), 184.0, 1.0, 40);
            // A double root at ⅓ decays as n ρ∞ⁿ.
            assert!(v.abs() < 40.0 * r.powi(39), "ρ∞ {r}: {v}");
        }
        // A slow mode at Ω = 0.1 over 10 periods (628 steps): Shi's ξ ≈ Ω/4 leaves
        // exp(−0.025 · 62.8) = 0.21 of the amplitude; the family keeps that damping (γ = 1).
        let amplitude = |s: &Scheme| {
            let (x, v) = oscillate(s, 1.0, 0.1, 628);
            (x * x + v * v).sqrt()
        };
        let a_shi = amplitude(&Scheme::SHI);
        assert!((a_shi - 0.21).abs() < 0.01, "{a_shi}");
        for r in [1.0 / 3.0, 0.5] {
            let a = amplitude(&Scheme::with_spectral_radius(r));
            assert!((a / a_shi - 1.0).abs() < 0.02, "ρ∞ {r}: {a} vs {a_shi}");
        }
    }

    #[test]
    fn constant_force_is_integrated_exactly_from_a_consistent_start() {
        // Free fall and a constant-acceleration slide are exact, as in Shi's step, when a0 starts
        // at M⁻¹ F; from a0 = 0 the dissipative steps lag by Δt² g (β − ½) at every step.
        for r in [1.0, 0.8, 0.5, 1.0 / 3.0] {
            let s = Scheme::with_spectral_radius(r);
            let mut f = Vec12::zeros();
            f[0] = -9.8;
            // Unit mass: the consistent a0 = M⁻¹ F is F itself.
            let mut k = Kinematics {
                velocity: Vec12::zeros(),
                acceleration: f,
            };
            let mut x = 0.0;
            let dt = 0.01;
            for _ in 0..200 {
                (x, k) = step1(&s, 0.0, x, &k, -9.8, dt);
            }
            assert!((x + 0.5 * 9.8 * 4.0).abs() < 1e-9, "ρ∞ {r}: {x}");
            assert!((k.velocity[0] + 9.8 * 2.0).abs() < 1e-9);
        }
    }
}
