//! The semi-implicit elastic step (seed Eqs. 13–20) and the end-of-step update of B̃ (seed
//! Eqs. 24–25): the elastic parts of the implicit-momentum stage [`Momentum`] (the `momentum`
//! module: the elastic solve, the projection and the deformation update as one stage with the
//! strategy `numerics.elastic.coupling`).
//!
//! # Equations
//!
//! The solid carries the modified left Cauchy–Green tensor `B̃ = φ_s^{1/2} B`, transported by
//! the upper-convected law (seed Eq. 8), `∂B̃/∂t + ∇·(V B̃) = L B̃ + B̃ Lᵀ` with
//! `L_ij = ∂V_i/∂x_j` (∇·V = 0), and exerts the elastic stress of a hyperelastic law
//! ([`efsi_laws_host`]): the law's stress at the solid's own B, weighted by the solid fraction
//! ("The interface" below; the seed's `τ(B̃)` for neo-Hookean). Axisymmetric, the hoop
//! component obeys `∂B̃_θθ/∂t + ∇·(V B̃_θθ) = 2 (u_r/r) B̃_θθ` (`L_θθ = u_r/r`) and the force
//! gains `−τ_θθ/r` on the radial momentum, both through the grid's hoop factor (zero in planar
//! geometry).
//!
//! # Time discretisation and the derivation of the implicit system
//!
//! Write `H(V; B) = L(V)·B + B·L(V)ᵀ`, linear in V. With Adams–Bashforth 2 for the advection
//! and the θ-weighted stretching (θ = ½: Crank–Nicolson, seed Eq. 13), every tensor of the step
//! is
//!
//! ```text
//!   B̃(V) = B̃ⁿ + E + θΔt H(V; B̃ⁿ),   E = −Δt [(1 + r/2) Aⁿ − (r/2) Aⁿ⁻¹] + (1 − θ)Δt H(Vⁿ; B̃ⁿ),
//! ```
//!
//! with `A = ∇·(V B̃)` and `r = Δt/Δt_prev`: `B̃^{n+1/3} = B̃(V^{n+1/3})` (Eq. 13),
//! `B̃^{n+2/3} = B̃(V^{n+2/3})` (Eq. 17) and `B̃^{n+1} = B̃(V^{n+1})` (Eq. 24). Subtracting,
//!
//! ```text
//!   B̃^{n+2/3} − B̃^{n+1/3} = θΔt H(δ; B̃ⁿ),   δ = V^{n+2/3} − V^{n+1/3}.        (Eq. 18)
//! ```
//!
//! **The seed's Eqs. 17–19 carry typos**: Eq. 17 must take `V^{n+2/3}` (with `V^{n+1/3}`
//! Eq. 18 would vanish), Eq. 18 has the two velocities in the opposite order, and Eq. 19 writes
//! `H(V^{n+1/3})` twice with opposite signs, where the two terms are `H(V^{n+2/3})` and
//! `H(V^{n+1/3})`, whose difference is `H(δ)`.
//!
//! The stress is linearised about `B̃^{n+1/3}` with the law's tangent `J = ∂τ/∂B̃` (Eq. 16),
//! `τ^{n+2/3} = τ^{n+1/3} + J : θΔt H(δ; B̃ⁿ)`, and the momentum step takes the weight α of
//! the new stress ("θ of the stress" below),
//!
//! ```text
//!   ρ δ/Δt = ∇·[α τ^{n+2/3} + (1 − α) τⁿ]
//!   ⇒  ρ δ/Δt − αθΔt ∇·[J : H(δ; B̃ⁿ)] = ∇·[α τ^{n+1/3} + (1 − α) τⁿ].
//! ```
//!
//! For a neo-Hookean solid near rest (`J = G I`, `B̃ ≈ I`, `H(δ) ≈ 2D(δ)`) the implicit term
//! is `2αθGΔt ∇·D(δ)`: **an extra viscosity `αθGΔt`** (`GΔt/2` at α = 1, θ = ½), which keeps
//! stiff solids stable at the flow's time step. Multiplied by the face volumes and joined by
//! the viscous step's implicit operator `K_v` ("Coupling with the viscous step") the system
//! is
//!
//! ```text
//!   (M − θ_v Δt K_v − αθΔt² K_J) δ = Δt·vol·∇·[α τ^{n+1/3} + (1 − α) τⁿ],
//! ```
//!
//! `K_J` not symmetric for a general law; it is solved to `‖r‖ ≤ tol · max(‖b‖, ‖M V^{n+1/3}‖)`
//! (`numerics.elastic.tolerance`). Then `V^{n+2/3} = V^{n+1/3} + δ` and
//! `B̃^{n+2/3} = B̃(V^{n+2/3})`.
//!
//! **Stability of the seed's trapezoid.** Eq. 15 as printed, `ρ δ/Δt = ½ ∇·(τ^{n+1/3} +
//! τ^{n+2/3})` with `τ^{n+1/3}` already holding a full explicit stretching step, is only
//! conditionally stable: for a 1-D shear wave in an inviscid solid (`u_t = G γ_y`,
//! `γ_t = u_y`, mode `k`, `s = kΔt√(G/ρ)`) its amplification factor is 0.9975, 0.77, 1.0,
//! 2.32, 3.39 at s = 0.1, 1, 2, 3, 5, unstable once `Δt > 2h/(π c)`. The seed's solids have a
//! viscosity `μ_s ≈ μ_f ρ_s/ρ_f` that hides this; Sugiyama's Couette test has `μ_s = 0`. The
//! step above is stable for every s and θ ≥ ½; the largest |amplification| of the wave's two
//! modes with the stress at the step's end (α = 1):
//!
//! ```text
//!   s =     0.1    1      2      3      5      20     100    400
//!   θ = ½   0.998  0.816  0.577  0.426  0.667  0.980  0.999  1.000
//!   θ = 0.6 0.997  0.791  0.542  0.395  0.250  0.649  0.666  0.667
//!   θ = ¾   0.996  0.756  0.500  0.359  0.225  0.315  0.333  0.333
//!   θ = 1   0.995  0.707  0.447  0.316  0.196  0.050  0.010  0.002
//! ```
//!
//! (`s` is π times the wave Courant number `Δt c/h` for the grid's shortest wave.) At `s ≫ 1`
//! the velocity's amplification tends to `−(1 − θ)/θ`: −1 at θ = ½ (an undamped two-step
//! oscillation, harmless while the wave cap keeps `s` small), −⅓ at the coupled step's ¾. At
//! small s the damping is `1 − s²/40` at θ = ½: a rate `∝ Δt`, first order in time.
//!
//! **θ of the stress.** With α = θ the step is the θ-method on the pair (velocity, strain): at
//! θ = ½ Crank–Nicolson, second order and undamped (`|amplification| = 1` at every s; the
//! energy argument is in the `coupled` module, "The stress at θ"). The split projection,
//! though, strains a solid it does not couple to (the `coupled` module), and an undamped stiff
//! solid gains energy from it. A split step therefore takes α = θ up to an elastic-wave Courant
//! number `Δt·c/h` of [`CN_WAVE_COURANT`] (`s ≤ π` for the grid's shortest wave), α = 1 from
//! [`DAMPED_WAVE_COURANT`] on, linear in between (`numerics.elastic.stress_theta` sets α
//! outright); a coupled step takes α = θ always. The cost: one more law evaluation a step,
//! `τ(Bⁿ)` without its tangent, where α < 1.
//!
//! **The end-of-step update is second order.** `B̃(V)` stretches `B̃ⁿ` by the new velocity,
//! `H(V^{n+1}; B̃ⁿ)`, where Crank–Nicolson stretches the new tensor, `H(V^{n+1}; B̃^{n+1})`: a
//! lag of `θΔt L^{n+1}(B̃^{n+1} − B̃ⁿ) = O(Δt²)` a step, first order over a run. The update
//! therefore makes one Picard pass, `B̃^{(1)} = B̃(V^{n+1})`, then
//! `B̃^{n+1} = B̃ⁿ + E + θΔt H(V^{n+1}; B̃^{(1)})` (`O(Δt³)` a step); the intermediate tensors
//! keep `H(V; B̃ⁿ)`, in which the implicit system is linear. A coupled step longer than the
//! split step's wave limit (`wave_courant`) makes no pass and ends with `B̃^{n+1} = B̃(V^{n+1})`,
//! the tensor its stiffness was solved with: the pass would add `θΔt (L ΔB̃ + ΔB̃ Lᵀ)`, a
//! strain no stiffness answered within the step, stored at G; such a step is first order in
//! time anyway (θ = ¾). The update also takes the rates `Aⁿ⁺¹`, `H(Vⁿ⁺¹; B̃ⁿ⁺¹)` of the next
//! step. The Couette cases' orders in space and time are measured by `cargo xtask
//! bench-paper` (`tests/src/paper/couette.rs`).
//!
//! # Coupling with the viscous step
//!
//! The viscous stage has already made `V^{n+1/3}` with its implicit operator `K_v`
//! (θ_v-scheme). Where viscosity relaxes faster than a step (`ρh²/μ ≪ Δt`, e.g. the fluid
//! beside an inviscid solid in Sugiyama's Couette test), splitting the two solves would leave
//! the elastic increment unrelaxed, the first fluid cell dragged with the solid at O(1) error.
//! The elastic system therefore includes `θ_v Δt K_v`: since `K_v V^{n+1/3} + K_v δ =
//! K_v V^{n+2/3}`, the viscous and elastic steps together are one implicit viscous–elastic
//! step.
//!
//! # Stress-free reference
//!
//! The stage divides `w (τ(B) − τ(I))`: the law's stress less its stress in the undeformed
//! state. The difference is isotropic — a pressure, which the projection absorbs (on the MAC
//! metric, hoop term included, the force of `q I` is exactly the discrete `∇q`) — but the rest
//! stress jumps across the interface (`G φ^{1/2} I` for neo-Hookean), and through the implicit
//! solve it would be smoothed into a non-gradient force. The tangent is unchanged.
//!
//! # The interface: the law on the solid's own B, the fraction on the stress
//!
//! A cell or corner on the interface holds solid (fraction `a`) and fluid side by side; the
//! solid part is deformed by the solid's own B, the fluid part not at all. The law is evaluated
//! **only on the solid's own B** — never on a mixture with the fluid's identity nor on a B
//! scaled by the fraction — and the fraction weights the stress:
//!
//! - **Normal components, at centres: in parallel** (iso-strain across the interface): the
//!   elastic stress is `w (τ(B) − τ(I))` with `w = φ^{1/2}`, whose neo-Hookean stress
//!   `G φ^{1/2} B` is the seed's `τ(B̃)`; the tangent is `w J(B)`, positive wherever the law's
//!   is. (The law on `B̃` itself, as the seed writes it, is right only for a law linear in B:
//!   Saint Venant–Kirchhoff on `φ^{1/2}B` has the shear stiffness `μ(2φ^{1/2} − 1)`, negative
//!   for `φ < ¼`.)
//! - **Shear, at corners: in series** ("Interface corners" below): the law sees the solid's
//!   normal components as the **solid-weighted** average of the four cells' (each weighted by
//!   the PLIC share of solid in its quarter next to the corner), and its shear stress counts
//!   with the series weight `a/(aκ)`.
//!
//! So the stress applied anywhere on the interface is the law's stress at the solid's own
//! deformation times a stated weight, whatever the law; for neo-Hookean it is the seed's to
//! round-off. The strain energy is weighted alike, `∫ w W(B) dV`. B and its rates are
//! transported as B (B̃ and B obey the same law because φ_s is materially conserved). Cells
//! with less solid than `PHI_MIN` (1e-3) count as fluid: B = I, no stress.
//!
//! # Pure fluid: the identity also when the rates are taken
//!
//! In fluid (`w = 0`) B is the identity and its rates zero. The end-of-step update stretches B
//! wherever it transports it, fluid cells near the solid included, and would leave there
//! `B = I + θΔt (L_f + L_fᵀ)`, one step of the fluid's velocity gradient, which reaches the
//! solid through the next step's upwind advection at its trailing interface and stays in the
//! cells it enters at its leading one: `≈ 2θΔt D_f` of strain per cell the interface crosses,
//! stored at G, energy growing like `Δt²`. The update therefore resets the fluid's B to the
//! identity **before** it takes the rates. Only the rates and the cells the solid enters
//! change; the stress and the energy weigh the fluid by `w = 0`. Asserted by
//! `tests/tests/elastic.rs` (`a_stiff_sphere_falling_clear_of_the_wall_keeps_no_strain_at_a_large_coupled_cap`).
//!
//! # Interface corners: the shear in series
//!
//! Across an interface solid and fluid shear **in series**: one shear stress, the shear rate
//! shared, `2D = a·2D_s + (1 − a)·2D_f`. With a Kelvin–Voigt solid `τ = τ_e(B) + μ_s 2D_s` and
//! a Newtonian fluid `τ = μ_f 2D_f`,
//!
//! ```text
//!   τ = τ_e/κ + μ_h 2D,   2D_s = (2D − (1 − a) τ_e/μ_f) / (aκ),
//!   aκ = a + μ_s (1 − a)/μ_f,   μ_h = μ_s μ_f / (a μ_f + (1 − a) μ_s)  (harmonic mean),
//! ```
//!
//! so at such a corner the law sees the solid's own B, its shear stress counts `1/κ`, the
//! viscous stage's corner viscosity is the harmonic mean (`viscous_operator`), and B₁₂ is
//! stretched by the solid's shear rate `2D/(aκ)` less a relaxation `r τ_e`
//! (`r = (1 − a)/(μ_f aκ)`): the fluid's share of a sustained shear. The solid's gradient
//! differs from the corner's only across the interface: with `n` the interface normal (∝ ∇φ
//! over the four cells) the extra shear rate goes to `L₁₂ = ∂u/∂y` by the share `n_y²` and to
//! `L₂₁ = ∂v/∂x` by `n_x²`. The cells around the corner hold the same solid, so their normal
//! components are stretched by the corners' solid gradients too (`Ḃ₁₁ = 2 L₁₂ B₁₂`,
//! `Ḃ₂₂ = 2 L₂₁ B₁₂`, the relaxation explicit at Bⁿ). The relaxation is a θ_r-step linearised
//! with the law's `∂τ₁₂/∂B₁₂` at Bⁿ, which keeps `B₁₂(V)` affine in V:
//! `B₁₂ = q (Bⁿ + E' + θΔt H(V; Bⁿ))`, `q = 1/(1 + θ_r z)`, `z = Δt r b̄ J₁₂₁₂`, `E'` the
//! explicit part less the linearisation's remainder (`Deformation::relax` holds q), with
//! `θ_r = ½ + ½ z/(1 + z)`: trapezoidal where the relaxation is slow over a step (second order
//! in time), backward Euler where it is stiff (a solid in air, `z ≫ 1`), monotone for every z
//! (the amplification `(1 − (1 − θ_r) z)/(1 + θ_r z)` lies in `(0, 1)`).
//!
//! The corner's solid fraction `a` is the solid volume of the four quarter cells around it
//! over theirs, each quarter cut by its cell's PLIC line (Youngs normal, as the VOF step
//! reconstructs); a corner whose quarters hold no solid carries no elastic shear. A parallel
//! mixture at the corner instead (the seed's `φ^{1/2}`-weighted stress beside the averaged
//! viscosity) lets elasticity and viscosity both act over the whole corner: an O(1) error in
//! the interface shear, first order overall (Sugiyama's Couette test, `cases/oscillating_couette*`).
//!
//! **Edges in three dimensions: the midpoint section.** An `(a, b)`-edge is a corner extruded
//! along the third axis `c`. Across the interface solid and fluid shear in series, but along
//! the edge the sections `ξ_c = const` lie side by side: in parallel, each with the series
//! closure of its own solid fraction, the edge's stress their average along it. The edge takes
//! that average at its midpoint (one point): `a` is the solid area of the four quarter squares
//! around the edge in the a–b section through its midpoint (the cells' centres along `c`),
//! each cut by the trace of its cell's PLIC plane, `n_a ξ_a + n_b ξ_b ≤ α − n_c h_c/2`. The
//! quarter cells' volume instead (each the whole cell long along `c`) is cut wherever the
//! surface is oblique along the edge (`n_c ≠ 0`), though the edge's own section may be solid:
//! every edge joining the surface cells of such a surface to the bulk would then be in series,
//! their elastic shear relaxed within a step, and the surface cells held to the bulk by
//! nothing but the normal stresses. A field uniform along `c` has the same fraction either
//! way: a planar interface extruded along the third axis gives the planar corners.
//!
//! # Space discretisation
//!
//! Staggered like the viscous stress: `B̃₁₁, B̃₂₂, B̃₃₃` and `τ₁₁, τ₂₂, τ₃₃` at cell centres,
//! `B̃₁₂`, `τ₁₂` at corners, so `∂τ₁₂/∂y` on a u-face is a compact difference. `L₁₁, L₂₂, L₃₃`
//! live at centres, `L₁₂ = ∂u/∂y`, `L₂₁ = ∂v/∂x` at corners; a component needed at the other
//! location is the average of its four neighbours. The shear rate is a two-point difference
//! near the interface and a four-point one in the solid's bulk, whose dispersion cancels the
//! two-point stress divergence's, so a shear wave crossing the solid lags by `O(h⁴)` in phase
//! (`Kernels::gradient_in`). The law is evaluated in batches
//! (centres, and the edges of each shear pair). Advection `∇·(V B̃)` is conservative with van Leer limited upwind
//! face values, as the momentum advection.
//!
//! **Three dimensions.** B̃ has six components ([`Deformation`]): the normal ones at centres
//! and each shear pair `B̃_ab` on the edges where the viscous operator puts `τ_ab`
//! (`viscous_operator::SHEAR`): `B̃₁₂` on the xy-edges (the corners extruded along z), `B̃₂₃`
//! on the yz-edges, `B̃₁₃` on the xz-edges. `L_aa` lives at centres, `L_ab` and `L_ba` on the
//! `(a, b)`-edges (the four-point bulk stencil in each edge family's plane), and one kernel
//! over the grid's shear pairs gives the gradient, the stretching (the third axis's terms
//! `L_ac B̃_cb + B̃_ac L_bc` from the neighbouring edge families, `transport`), the advection
//! and the end-of-step update in two and three dimensions; a planar field extruded along a
//! periodic z gives the planar values. The law sees the full tensor `[11, 22, 33, 12, 23, 13]`
//! (law ABI version 2; a version-1 library is refused in a 3-D scene): at a centre the cell's
//! normal components and each shear the mean of the cell's four edges of its pair; on an
//! `(a, b)`-edge the solid-weighted normal components of its four cells, its own shear, and
//! each other shear the mean of the four edges of its pair around it (`stress`). The stress
//! divergence on the faces normal to `a` is `Σ_b A_b Δ_b τ_ab` (`A_b` the face area across
//! `b`), the implicit operator and both preconditioners act on u, v and w, and the coupled step
//! uses the seven-point Poisson operator of the projection. "Interface corners" holds on every
//! edge family in its own plane: an `(a, b)`-edge's solid fraction is the solid area of its
//! four quarter squares in its midpoint section ("Edges in three dimensions" above), cut by the
//! trace of the cell's PLIC plane (the mixed Youngs–centred normal, as the VOF step
//! reconstructs), its interface normal's
//! share `n_b²/(n_a² + n_b²)`, and its shear relaxes as the corners' does; the relaxation's
//! change of the solid's `L_ab` (`L_ba`) stretches, besides the normal components, the shear of
//! the pair `(a, c)` (`(b, c)`) on the four edges around, `Ḃ_ac = L_ab B_bc`. The strain energy
//! takes the principal axes of each cell's B by Jacobi rotations. Sugiyama's Couette layer
//! sheared along `(cos 30°, 0, sin 30°)` (`cases/oscillating_couette_3d.ron`) gives the planar
//! error along the wall's motion (`tests/tests/couette_3d.rs`).
//!
//! # Several bodies
//!
//! In a scene of several bodies each body with a law keeps its own B (weighted by its own
//! fraction `φ_k`, reset to the identity outside it), its own law and its own interface
//! weights; everything above holds per body, and the bodies' stresses and tangents add: the
//! right-hand side is `Δt·vol·∇·Σ_k τ_k`, the implicit operator `Σ_k K_J,k` (each body's
//! increment stretched by its own `B_kⁿ`), the preconditioners' stiffness the sum of the
//! bodies'. The `bodies` module holds the rule, the storage ([`BodyDeformations`]) and the
//! limits. A scene of one body runs exactly the single body's arithmetic.
//!
//! # Solve
//!
//! BiCGSTAB (van der Vorst 1992), right-preconditioned (`numerics.elastic.preconditioner`):
//! - `Multigrid`: the implicit tangent acts like a viscosity, so the SPD approximation
//!   `M − vol·∇·(2ηD)`, `η = θ_v Δt μ + αθΔt² G_eff` (`Kernels::stiffness`: `G_eff` from the
//!   tangent's diagonal and B̃, the series factors at interface corners), is preconditioned by
//!   one multigrid V-cycle on each of its u–u and v–v blocks (`block_multigrid`), on a window
//!   around the solid (the Jacobi diagonal elsewhere). Its iterations hardly grow with the
//!   elastic-wave Courant number `Δt√(G/ρ)/h`; Jacobi's do.
//! - `Jacobi`: a bound of the diagonal (the mass plus the stiffness over `h²`).
//! - `Auto` (the default): `Multigrid`, but `Jacobi` in split steps of scenes with a periodic
//!   boundary: the red–black smoother keeps a flow uniform along the periodic direction
//!   uniform only to the tolerance, Jacobi exactly. The coupled step always takes `Multigrid`.
//!
//! The increment's stress `J : (w ΔB)` vanishes outside the solid, so the operator computes
//! gradients, stretching and tangent only over the solid's bounding box (plus the ring the
//! stencils read): the elastic part costs the solid's size, not the grid's. B is transported
//! only within a few cells of any material (`Kernels::near_c`), where it can reach the solid
//! within a step. The viscous part is applied over the whole grid by the one viscous operator
//! (`viscous_operator`). Loops over rows and the solver's reductions run in parallel with fixed
//! results: the iterates are bit-identical on any number of threads.
//!
//! # Stability and limits
//!
//! The implicit step is stable for every elastic-wave Courant number (above, θ ≥ ½); the
//! explicit AB2 advection follows the flow's CFL. What caps Δt is the split projection: its
//! correction strains the solid without the stiffness answering within the step (the
//! `coupled` module), so a split step is capped at `wave_courant` elastic-wave Courant numbers
//! ([`MAX_WAVE_COURANT`]), a coupled step at `coupled_wave_courant` for accuracy
//! ([`ElasticOptions`]). The cap uses the law's stiffness at rest: a law that stiffens under
//! strain is under-limited where it is deformed; `h` is the smallest cell size over the grid's
//! axes, and the stiffness at rest the largest diagonal entry of the tangent on the grid's
//! tensor (in-plane or full). A solid must be at least [`MIN_CELLS_ACROSS`] cells across (its
//! section's `4A/P` in two dimensions, its `6V/S` in three).
//!
//! # References
//!
//! - H. Esmailzadeh, M. Passandideh-Fard, *Numerical and experimental analysis of the
//!   fluid–structure interaction in presence of a hyperelastic body*, J. Fluids Eng. (2014) —
//!   the seed, Eqs. 8–25.
//! - K. Sugiyama et al., J. Comput. Phys. 230 (2011) 596 — the full Eulerian method, the
//!   oscillating Couette benchmark; S. Ii et al. (2011) — its implicit elastic term.
//! - H. A. van der Vorst, SIAM J. Sci. Stat. Comput. 13 (1992) 631 — BiCGSTAB.

use crate::faces::UnknownFaces;
use crate::viscous_operator::{SHEAR, shear_pairs};
use efsi_core::scene::{Boundary, Side};
use efsi_core::{BoundarySet, Field, FieldId, Grid, Index, Region, StageError};

mod bodies;
mod choice;
mod coupled;
mod deformation;
mod energy;
mod interface;
mod law;
mod limits;
mod momentum;
mod options;
mod outputs;
mod resource;
mod solve;
mod stress;
#[cfg(test)]
mod tests;
mod transport;
mod window;

pub(crate) use bodies::any_elastic;
pub use bodies::{BodyDeformations, Place};
pub(crate) use choice::may_couple;
use choice::{StepScheme, coupled_step, coupling};
pub use law::resolve_law;
pub use limits::MIN_CELLS_ACROSS;
pub use momentum::Momentum;
pub use options::{
    AUTO_COUPLED_GAIN, AUTO_STRAIN_SHARE, AUTO_WALL_CELLS, CN_WAVE_COURANT, DAMPED_WAVE_COURANT,
    DEFAULT_AUTO_COUPLED_WAVE_COURANT, DEFAULT_COUPLED_WAVE_COURANT, ElasticCoupling,
    ElasticOptions, ElasticPreconditioner, MAX_COUPLED_WAVE_COURANT, MAX_WAVE_COURANT,
};
pub use resource::Deformation;
use window::{Four, Window, cells_of_edge, edges_of_cell, plus};

/// The field the elastic stages own: the solid's tensor B and its history ([`Deformation`]).
pub const B: FieldId = FieldId::Stage("B");

/// Velocity gradients, stretching, advection, law batches and stress divergence on the
/// staggered layout.
struct Kernels {
    /// The grid the kernels run on: the whole grid, or a body's window
    /// ([`bodies::Place`]) as a grid of its own.
    grid: Grid,
    /// Its sides.
    bc: BoundarySet,
    /// The unknown faces of the whole grid and their compact order.
    faces: UnknownFaces,
    /// The whole grid's index of the kernels' cell `[0, 0, 0]` (zero on the whole grid).
    origin: Index,
    /// On a window, its place (`None` on the whole grid), and the velocity copied onto it (one
    /// field per axis) and the stiffness it adds into the preconditioners' ([`Kernels::stiffness`],
    /// centres then the edges of each shear pair).
    place: Option<bodies::Place>,
    vel: Vec<Field>,
    eta: Vec<Field>,
    /// L₁₁, L₂₂, L₃₃ at centres.
    lc: [Field; 3],
    /// Per shear pair `[a, b]` ([`shear_pairs`]), the solid's `L_ab = ∂u_a/∂x_b` and
    /// `L_ba` on its edges (the shear rate's interface share included: see
    /// [`Kernels::gradient_in`]).
    lk: Vec<[Field; 2]>,
    /// `φ^{1/2}` at centres.
    w: Field,
    /// Per shear pair, the interface weights of its edges.
    edge: Vec<EdgeWeights>,
    /// Per shear pair `[a, b]`, per centre, the solid fraction of each quarter of the cell in
    /// the a–b plane (on a three-dimensional grid in the section through the cell's centre
    /// along the third axis) cut by its PLIC line or plane's trace (lower-left, lower-right,
    /// upper-left, upper-right; `φ` itself in uncut cells and beyond the batch).
    quarter: Vec<[Field; 4]>,
    /// The fluid's and the solid's viscosities (scene values).
    mu_f: f64,
    mu_s: f64,
    /// The centres holding solid (`w > 0`, within `[−1, n]` along each axis) and, per shear
    /// pair, the edges touching them (the only ones with `w_k > 0`; [`Window::EMPTY`] past the
    /// grid's pairs), set by [`Kernels::set_weights`]: outside them the tangent's stress
    /// increment vanishes (it is weighted by `w`, `w_k`), so the elastic operator skips them.
    solid_c: Window,
    solid_k: [Window; 3],
    /// Per shear pair, the edges whose weights the last [`Kernels::set_weights`] set from the
    /// solid (`None` until the first, or after the fields were made): outside them the edge
    /// weights hold their no-solid values, so the next call resets these edges only.
    edges_set: Option<[Window; 3]>,
    /// The centres within [`NEAR`] cells of any material (`φ > 0`, flotsam included), set by
    /// [`Kernels::set_weights`], and the edges touching them ([`Window::edges`]): the
    /// deformation is transported there only. Elsewhere B stays the identity and its rates
    /// zero ([`Kernels::reset_fluid`]): a cell becomes solid only from a neighbour's material
    /// (the VOF step moves less than a cell per step), and its B and rates read B at most three
    /// cells beyond it (the advection's van Leer stencil), so the solid's deformation is the
    /// same as if B were transported everywhere.
    near_c: Window,
    /// Work space of [`Kernels::strain_energy`]: per solid cell, its weight, principal axes
    /// (cos, sin), the isochoric logarithms of the principal stretches and its volume.
    energy_cells: Vec<energy::EnergyCell>,
    /// The area of a face normal to each axis, `Π_{b≠a} h_b` over the grid's axes (the radius
    /// aside).
    area: [f64; 3],
    /// The components of the tensors the law sees: 4 (`[11, 22, 33, 12]`, law ABI version 1's
    /// [`efsi_laws_host::Sym`]) on a two-dimensional grid, 6 (`[11, 22, 33, 12, 23, 13]`, [`efsi_laws_host::Sym6`]) on a
    /// three-dimensional one.
    m: usize,
    /// Law batches, flat (`m` components, `m²` tangent entries per point, cell-major), sized for
    /// every centre within `[−1, n]` along each axis and, per shear pair, every edge touching
    /// one: the centres of `solid_c` and the edges of `solid_k`, line by line ([`Kernels::ci`],
    /// [`Window::region`]).
    cb: Vec<f64>,
    ct: Vec<f64>,
    cj: Vec<f64>,
    /// Which points of a batch's window are live ([`Kernels::batch`]); its capacity kept
    /// between steps.
    mask: Vec<bool>,
    kb: Vec<Vec<f64>>,
    kt: Vec<Vec<f64>>,
    kj: Vec<Vec<f64>>,
}

/// The interface weights of the edges of one shear pair `[a, b]` (the corners of a
/// two-dimensional grid; see "Interface corners" in the module docs, whose `n_y²` is `n_b²`).
struct EdgeWeights {
    /// The four cells' average of `φ^{1/2}` (zero exactly where the edge has no solid).
    wc: Field,
    /// The edge's B̃ weight `w_k` (1 with any solid, else 0), its solid shear-rate factor
    /// `s = 1/(aκ)`, stress factor `1/κ` and relaxation coefficient `r = (1 − a)/(μ_f a κ)`
    /// (`aκ` taken no less than a sliver's floor in `s` and `r`: see
    /// `interface::sliver_rates`).
    wk: Field,
    sf: Field,
    ks: Field,
    rc: Field,
    /// The weights of its four cells ([`cells_of_edge`]) in its normal components of B: each
    /// cell's solid quarter next to the edge, over their sum (cells without deformation,
    /// `w = 0`, weigh nothing).
    kwt: [Field; 4],
    /// The share `n_b²/(n_a² + n_b²)` of the interface's normal (from the four cells' φ; ½
    /// where φ is uniform): the part of the solid's extra shear rate that goes to `L_ab`, the
    /// rest going to `L_ba`.
    share: Field,
}

impl EdgeWeights {
    fn new(grid: &Grid) -> Self {
        EdgeWeights {
            wc: Field::zeros(grid),
            wk: Field::zeros(grid),
            sf: Field::zeros(grid),
            ks: Field::zeros(grid),
            rc: Field::zeros(grid),
            kwt: std::array::from_fn(|_| Field::zeros(grid)),
            share: Field::zeros(grid),
        }
    }
}

/// `PAIR[a][b]`: the index in [`SHEAR`] of the pair of axes `a ≠ b` (the diagonal unused).
const PAIR: [[usize; 3]; 3] = [[0, 0, 2], [0, 0, 1], [2, 1, 0]];

/// The velocity `[u, v]`, or `[u, v, w]` with a third component (a state's `w`): a slice of
/// field references on the stack, so a step allocates nothing.
struct Velocity<'a> {
    fields: [&'a Field; 3],
    len: usize,
}

impl<'a> std::ops::Deref for Velocity<'a> {
    type Target = [&'a Field];
    fn deref(&self) -> &[&'a Field] {
        &self.fields[..self.len]
    }
}

/// [`Velocity`] of `u`, `v` and, with a third component, `w`.
fn velocity<'a>(u: &'a Field, v: &'a Field, w: Option<&'a Field>) -> Velocity<'a> {
    match w {
        Some(w) => Velocity {
            fields: [u, v, w],
            len: 3,
        },
        None => Velocity {
            fields: [u, v, v],
            len: 2,
        },
    }
}

/// Cells with less solid than this carry no deformation (B = I, no stress): VOF flotsam and
/// slivers of an interface whose B the mixed-cell velocity gradient spoils. Their stress,
/// weighted by `φ^{1/2}`, would act on a face whose mass is the fluid's (`φρ_s ≪ ρ_f` at a
/// density ratio of 1000), which flung air at tens of m/s as a sphere left the substrate.
const PHI_MIN: f64 = 1e-3;

/// How many cells beyond any material the deformation is transported ([`Kernels::near_c`]):
/// one cell the material may reach in a step, three more its B and rates read.
const NEAR: isize = 4;

/// The weights of the four cells of each edge of `line` ([`cells_of_edge`]) in the edge's
/// normal components ([`EdgeWeights::kwt`]): with [`Four::weighted`], the solid-weighted
/// average there of a centre field, the interface-consistent value of a normal component (see
/// "Interface corners").
#[inline(always)]
fn corner_weights<'a>(kwt: &'a [Field; 4], line: &efsi_core::Line) -> [&'a [f64]; 4] {
    let on = |m: usize| kwt[m].at(line, [0; 3]);
    [on(0), on(1), on(2), on(3)]
}

/// A field's values at the indices of `line`.
#[inline(always)]
fn on<'a>(f: &'a Field, line: &efsi_core::Line) -> &'a [f64] {
    f.at(line, [0; 3])
}

impl Kernels {
    /// Kernels on the whole grid.
    fn new(grid: &Grid, bc: &BoundarySet, mu_f: f64, mu_s: f64) -> Self {
        Self::on(grid, bc, UnknownFaces::new(grid, bc), mu_f, mu_s)
    }

    /// Kernels on the window `place` of `parent` (sides `sides`, `bc` of them), with the
    /// whole grid's unknown faces.
    fn windowed(
        parent: &Grid,
        bc: &BoundarySet,
        sides: &efsi_core::scene::Boundaries,
        place: bodies::Place,
        mu_f: f64,
        mu_s: f64,
    ) -> Self {
        let grid = place.grid(parent);
        let wbc = BoundarySet::new(&place.sides(parent, sides), &grid);
        let mut k = Self::on(&grid, &wbc, UnknownFaces::new(parent, bc), mu_f, mu_s);
        k.origin = place.origin();
        k.place = Some(place);
        k.vel = (0..grid.dims()).map(|_| Field::zeros(&grid)).collect();
        k.eta = (0..k.edge.len() + 1).map(|_| Field::zeros(&grid)).collect();
        k
    }

    fn on(grid: &Grid, bc: &BoundarySet, faces: UnknownFaces, mu_f: f64, mu_s: f64) -> Self {
        let n = grid.n();
        let nc: usize = (0..grid.dims()).map(|a| n[a] + 2).product();
        let pairs = shear_pairs(grid.dims()).len();
        let m = 3 + pairs;
        let batch = |len: usize| (0..pairs).map(|_| vec![0.0; len]).collect::<Vec<_>>();
        Kernels {
            grid: grid.clone(),
            bc: bc.clone(),
            faces,
            origin: [0; 3],
            place: None,
            vel: Vec::new(),
            eta: Vec::new(),
            lc: std::array::from_fn(|_| Field::zeros(grid)),
            lk: (0..pairs)
                .map(|_| std::array::from_fn(|_| Field::zeros(grid)))
                .collect(),
            w: Field::zeros(grid),
            edge: (0..pairs).map(|_| EdgeWeights::new(grid)).collect(),
            quarter: (0..pairs)
                .map(|_| std::array::from_fn(|_| Field::zeros(grid)))
                .collect(),
            mu_f,
            mu_s,
            solid_c: Window::EMPTY,
            solid_k: [Window::EMPTY; 3],
            edges_set: None,
            near_c: Window::EMPTY,
            energy_cells: Vec::new(),
            area: std::array::from_fn(|a| {
                let h = grid.h();
                let mut o = (0..grid.dims()).filter(|&b| b != a);
                let first = o.next().map_or(1.0, |b| h[b]);
                o.fold(first, |s, b| s * h[b])
            }),
            m,
            cb: vec![0.0; m * nc],
            ct: vec![0.0; m * nc],
            cj: vec![0.0; m * m * nc],
            mask: Vec::with_capacity(nc),
            kb: batch(m * nc),
            kt: batch(m * nc),
            kj: batch(m * m * nc),
        }
    }

    /// The centres and the edges of each shear pair whose gradients [`Kernels::stretch_in`]
    /// reads at the centres `c` and their edges: one centre more all round (within
    /// `[−1, n]` along each axis), and along an edge family's nodal axes the low and high
    /// edges of every centre of `c` (ghost edges included: the axis's odd B̃₁₂ is not zero
    /// there), along its centred axis the centres' range (the xz- and yz-edges beside an
    /// xy-edge enter its stretching on a three-dimensional grid).
    /// The edge windows come as a fixed array, [`Window::EMPTY`] past the grid's shear pairs
    /// (no allocation in a step).
    fn gradient_windows(&self, c: Window) -> (Window, [Window; 3]) {
        let pairs = shear_pairs(self.grid.dims());
        let mut edges = [Window::EMPTY; 3];
        if c.points() == 0 {
            return (Window::EMPTY, edges);
        }
        let (n, dims) = (self.grid.n(), self.grid.dims());
        let (lo, hi) = (c.lo(), c.hi());
        let cells = Window::boxed(
            std::array::from_fn(|a| if a < dims { (lo[a] - 1).max(-1) } else { 0 }),
            std::array::from_fn(|a| {
                if a < dims {
                    (hi[a] + 1).min(n[a] as isize)
                } else {
                    0
                }
            }),
        );
        for (edge, &(_, at)) in edges.iter_mut().zip(pairs) {
            let nodal = at.nodal();
            let pick = |a: usize, node: isize, cell: isize| match nodal[a] {
                1 => node,
                _ => cell,
            };
            *edge = Window::boxed(
                std::array::from_fn(|a| pick(a, lo[a], cells.lo()[a])),
                std::array::from_fn(|a| pick(a, hi[a] + 1, cells.hi()[a])),
            );
        }
        (cells, edges)
    }

    /// Batch index of centre `at` of the solid's window [`Kernels::solid_c`] (the law batches
    /// hold the window's points, line by line).
    #[inline(always)]
    fn ci(&self, at: Index) -> usize {
        let c = self.solid_c;
        debug_assert!(c.contains3(at), "centre {at:?} outside {c:?}");
        c.offset(at)
    }

    /// A law's error with the point it names (an entry of the centre batch, or of the edge
    /// batch of the shear pair `edge`) turned into the grid's index and position.
    fn locate(&self, e: efsi_laws_host::LawError, edge: Option<usize>) -> String {
        let Some(q) = e.cell else {
            return e.to_string();
        };
        let g = &self.grid;
        let text = efsi_laws_host::LawError { cell: None, ..e }.to_string();
        let c = edge.map_or(self.solid_c, |p| self.solid_k[p]);
        let at = c.point(q);
        let (ijk, xyz) = if g.is_3d() {
            ("(i, j, k)", "(x, y, z)")
        } else {
            ("(i, j)", "(x, y)")
        };
        let list = |v: &mut dyn Iterator<Item = String>| v.collect::<Vec<_>>().join(", ");
        // The whole grid's index (the kernels' grid may be a body's window, whose positions
        // are the grid's).
        let on_grid = plus(at, self.origin);
        let shown = list(&mut on_grid[..g.dims()].iter().map(|i| i.to_string()));
        let pos = |a: usize| {
            let nodal = edge.is_some_and(|p| SHEAR[p].1.nodal()[a] == 1);
            match (a, nodal) {
                (0, true) => g.xf(at[0]),
                (0, false) => g.xc(at[0]),
                (1, true) => g.yf(at[1]),
                (1, false) => g.yc(at[1]),
                (_, true) => g.zf(at[2]),
                (_, false) => g.zc(at[2]),
            }
        };
        let p = list(&mut (0..g.dims()).map(|a| format!("{:.6e}", pos(a))));
        match edge {
            Some(0) if !g.is_3d() => format!("{text} at corner {ijk} = ({shown}), {xyz} = ({p})"),
            Some(_) => format!("{text} at edge {ijk} = ({shown}), {xyz} = ({p})"),
            None => format!("{text} in cell {ijk} = ({shown}), centre {xyz} = ({p})"),
        }
    }

    /// Fill the ghosts of a staggered tensor.
    fn fill_ghosts(&self, t: &mut [Field]) {
        let (normal, shear) = t.split_at_mut(3);
        for f in normal {
            self.bc.fill_scalar(&self.grid, f, false);
        }
        for (f, &(axes, _)) in shear.iter_mut().zip(shear_pairs(self.grid.dims())) {
            fill_edge(&self.bc, &self.grid, f, axes);
        }
    }
}

/// Fill the ghosts of a shear component on the edges of the pair `axes` (the corners of a
/// two-dimensional grid: a staggering of this stage's, which the core's boundary conditions do
/// not know), one axis after the other. Along the pair's axes (nodal, the boundary on an edge
/// line): wrap at periodic sides, even reflection about the boundary line elsewhere, except at
/// the axis and at a symmetry plane, where the component is odd (it changes sign with the
/// normal coordinate) and zero on the boundary. Along the third axis (centred): wrap at
/// periodic sides, even reflection about the boundary face elsewhere, as a cell scalar.
fn fill_edge(bc: &BoundarySet, grid: &Grid, f: &mut Field, axes: [usize; 2]) {
    let whole = Region::whole(grid);
    let (lo, hi, n) = (whole.lo(), whole.hi(), grid.n());
    for axis in 0..grid.dims() {
        let n = n[axis] as isize;
        let ghosts = -lo[axis];
        let at = |base: Index, a: isize| {
            let mut i = base;
            i[axis] = a;
            i
        };
        let side = |high| bc.get(Side::normal_to(axis, high));
        let periodic = *side(false) == Boundary::Periodic;
        let nodal = axes.contains(&axis);
        let odd =
            |high| nodal && matches!(side(high), Boundary::Axis | Boundary::Symmetry) && !periodic;
        let sign = |high| if odd(high) { -1.0 } else { 1.0 };
        let (s0, s1) = (sign(false), sign(true));
        let bases = whole.range(axis, 0, 1);
        debug_assert!(hi[axis] - lo[axis] >= n + 2 * ghosts);
        for l in (0..bases.lines()).map(|m| bases.line(m)) {
            for base in l.indices() {
                match (nodal, periodic) {
                    (true, true) => {
                        f[at(base, n)] = f[at(base, 0)];
                        for g in 1..=ghosts {
                            f[at(base, -g)] = f[at(base, n - g)];
                            f[at(base, n + g)] = f[at(base, g)];
                        }
                    }
                    (true, false) => {
                        if s0 < 0.0 {
                            f[at(base, 0)] = 0.0;
                        }
                        if s1 < 0.0 {
                            f[at(base, n)] = 0.0;
                        }
                        for g in 1..=ghosts {
                            f[at(base, -g)] = s0 * f[at(base, g)];
                            f[at(base, n + g)] = s1 * f[at(base, n - g)];
                        }
                    }
                    (false, true) => {
                        for g in 1..=ghosts {
                            f[at(base, -g)] = f[at(base, n - g)];
                            f[at(base, n - 1 + g)] = f[at(base, g - 1)];
                        }
                    }
                    (false, false) => {
                        for g in 1..=ghosts {
                            f[at(base, -g)] = f[at(base, g - 1)];
                            f[at(base, n - 1 + g)] = f[at(base, n - g)];
                        }
                    }
                }
            }
        }
    }
}

fn missing() -> StageError {
    StageError {
        stage: "elastic".into(),
        message: "B̃ is not allocated".into(),
    }
}

fn err(stage: &str, message: String) -> StageError {
    StageError {
        stage: stage.into(),
        message,
    }
}

/// [`err`] of body `b`'s law or kernels: in a scene of several bodies the message names the
/// body and its place in the scene (several may share a law).
fn body_err(stage: &str, b: &bodies::ElasticBody, message: String) -> StageError {
    match b.index {
        Some(_) => err(stage, format!("body `{}` ({}): {message}", b.name, b.path)),
        None => err(stage, message),
    }
}
