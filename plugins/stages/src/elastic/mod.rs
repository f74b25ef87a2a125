//! The semi-implicit elastic stage (seed Eqs. 13–20) and the end-of-step update of B̃
//! (seed Eqs. 24–25).
//!
//! # Equations
//!
//! The solid carries the modified left Cauchy–Green tensor `B̃ = φ_s^{1/2} B`, transported by
//! the upper-convected law (seed Eq. 8), `∂B̃/∂t + ∇·(V B̃) = L B̃ + B̃ Lᵀ` with
//! `L_ij = ∂V_i/∂x_j` (∇·V = 0), and exerts the elastic stress of a hyperelastic law
//! ([`efsi_laws_host`]): the law's stress at the solid's own B, weighted by the solid fraction
//! (see "The interface" below; the seed's `τ(B̃)` for neo-Hookean). Axisymmetric, the hoop component obeys `∂B̃_θθ/∂t + ∇·(V B̃_θθ) =
//! 2 (u_r/r) B̃_θθ`, i.e. `L_θθ = u_r/r`, and the force gains the hoop term `−τ_θθ/r` on the
//! radial momentum — both through the grid's hoop factor, zero in planar geometry.
//!
//! # Time discretisation and the derivation of the implicit system
//!
//! Write `H(V; B) = L(V)·B + B·L(V)ᵀ`, linear in V. With Adams–Bashforth 2 for the advection and
//! Crank–Nicolson for the stretching (seed Eq. 13), every intermediate tensor of the step is
//!
//! ```text
//!   B̃(V) = B̃ⁿ + E + (Δt/2) H(V; B̃ⁿ),   E = −Δt [(1 + r/2) Aⁿ − (r/2) Aⁿ⁻¹] + (Δt/2) H(Vⁿ; B̃ⁿ),
//! ```
//!
//! with `A = ∇·(V B̃)` and `r = Δt/Δt_prev`: `B̃^{n+1/3} = B̃(V^{n+1/3})` (Eq. 13),
//! `B̃^{n+2/3} = B̃(V^{n+2/3})` (Eq. 17 — the seed prints `V^{n+1/3}` there, a typo: otherwise
//! Eq. 18 would vanish) and `B̃^{n+1} = B̃(V^{n+1})` (Eq. 24). Subtracting,
//!
//! ```text
//!   B̃^{n+2/3} − B̃^{n+1/3} = (Δt/2) H(δ; B̃ⁿ),   δ = V^{n+2/3} − V^{n+1/3}          (Eq. 18, corrected)
//! ```
//!
//! (the seed's Eq. 18 has the two velocities in the opposite order). The seed's elastic momentum
//! step is trapezoidal (Eq. 15), `ρ δ/Δt = ½ ∇·(τ^{n+1/3} + τ^{n+2/3})`, with the stress
//! linearised about `B̃^{n+1/3}` by the law's tangent `J = ∂τ/∂B̃` (Eq. 16):
//! `τ^{n+2/3} = τ^{n+1/3} + J : (Δt/2) H(δ; B̃ⁿ)`. (Its Eq. 19 writes the same `H(V^{n+1/3})`
//! twice with opposite signs, which would cancel; the two terms are `H(V^{n+2/3})` and
//! `H(V^{n+1/3})`, whose difference is `H(δ)`.)
//!
//! **That trapezoid is only conditionally stable.** For a 1-D shear wave in an inviscid solid
//! (`u_t = G γ_y`, `γ_t = u_y`, Fourier mode `k`, `s = kΔt√(G/ρ)`), `τ^{n+1/3}` already holds a
//! full explicit stretching step, and the amplification factor of the seed's step is 0.9975,
//! 0.77, 1.0, 2.32, 3.39 at s = 0.1, 1, 2, 3, 5: it blows up once `Δt > 2h/(π c)` (we saw it at
//! 256 cells in the Couette test, where `s_max ≈ 2.9`). The seed's solids have
//! `μ_s ≈ μ_f ρ_s/ρ_f`, whose viscosity hides this; Sugiyama's Couette test has `μ_s = 0`.
//! efsi therefore takes the stress at the end of the elastic step,
//!
//! ```text
//!   ρ δ/Δt = ∇·τ^{n+2/3},   τ^{n+2/3} = τ^{n+1/3} + J : (Δt/2) H(δ; B̃ⁿ)
//!   ⇒  ρ δ/Δt − (Δt/2) ∇·[J : H(δ; B̃ⁿ)] = ∇·τ^{n+1/3},
//! ```
//!
//! with amplification 0.9975, 0.82, 0.58, 0.43, 0.67, 0.98 at s = 0.1, 1, 2, 3, 5, 20: stable
//! for every Δt, the same damping as the seed's where both are stable (`1 − s²/40` at small s:
//! a damping rate `∝ Δt`, first order in time, which is why a slow step weights the stress as
//! below, "θ of the stress"),
//! and for a neo-Hookean solid near rest (`J = G I`, `B̃ ≈ I`, `H(δ) ≈ 2D(δ)`) the implicit term
//! is `GΔt ∇·D(δ)`: an extra viscosity `GΔt/2`, which is what keeps stiff solids stable at the
//! flow's time step. Multiplied by the face volumes the system is
//! `(M − (Δt²/2) K_J) δ = Δt·vol·∇·τ^{n+1/3}`; `K_J` is not symmetric for a general law, so it
//! is solved with BiCGSTAB (see "Solve" below), to `‖r‖ ≤ tol · max(‖b‖, ‖M V^{n+1/3}‖)`
//! (scene `numerics.elastic.tolerance`, default 1e-6). Finally `V^{n+2/3} = V^{n+1/3} + δ` and
//! `B̃^{n+2/3} = B̃(V^{n+2/3})`; after the projection the [`DeformationUpdate`] stage sets
//! `B̃^{n+1} = B̃(V^{n+1})` (Eq. 25 ≡ Eq. 24) and the rates `Aⁿ⁺¹`, `H(Vⁿ⁺¹; B̃ⁿ⁺¹)` the next
//! step needs.
//!
//! **The end-of-step update is second order.** `B̃(V)` stretches `B̃ⁿ` by the new velocity,
//! `H(V^{n+1}; B̃ⁿ)`, where Crank–Nicolson stretches the new tensor, `H(V^{n+1}; B̃^{n+1})`:
//! a lag of `(Δt/2) L^{n+1}(B̃^{n+1} − B̃ⁿ) = O(Δt²)` a step, first order over a run. The
//! deformation stage therefore makes one Picard pass: `B̃^{(1)} = B̃(V^{n+1})`, then
//! `B̃^{n+1} = B̃ⁿ + E + (Δt/2) H(V^{n+1}; B̃^{(1)})` (`O(Δt³)` a step). The Mooney–Rivlin
//! Couette case (64 cells, Δt = 0.001) erred by 2.09e-3 with the lag (5.8e-4 at Δt/4: the
//! error was the time step's, not the interface's) and by 3.5e-4 with the pass. The
//! intermediate tensors of the elastic step keep `H(V; B̃ⁿ)`: the implicit system is
//! linear in V only so. A coupled step longer than the split step's wave limit
//! (`wave_courant`) makes no pass: it ends with `B̃^{n+1} = B̃(V^{n+1})`, the tensor its
//! implicit stiffness was solved with. The pass changes `B̃` by
//! `θΔt (L ΔB̃ + ΔB̃ Lᵀ)`, a strain no stiffness answered within the step, which the next step
//! finds stored at G: in a stiff solid at tens of elastic-wave Courant numbers it is most of the
//! strain energy a rigid motion leaves (the stability map's sphere at G = 1e9 Pa falling at 50:
//! 9.2e-3 of its kinetic energy with the pass, 2.0e-3 without). A coupled step is first order
//! in time for the solid anyway (θ = ¾ below), so the pass's `O(Δt³)` buys little there;
//! within the split step's limit, where the pass is known stable, a coupled step makes it
//! (with `Coupled`, the Mooney–Rivlin Couette case at 64 cells errs by 9.8e-4 with it, 2.0e-3
//! without).
//!
//! **θ of the stretching.** The step above is Crank–Nicolson in the stretching (the `Δt/2`
//! weights). With `numerics.elastic.theta` = θ the weights are `(1 − θ)Δt` on `H(Vⁿ)` and
//! `θΔt` on `H(V)`, and the implicit term `θΔt² K_J`: for the 1-D wave at `s ≫ 1` the
//! velocity's amplification tends to `−(1 − θ)/θ` — −1 at θ = ½ (an undamped two-step
//! oscillation, harmless while the wave cap keeps `s` small), −⅓ at the coupled step's
//! default ¾ (see `coupled`). The largest |amplification| of the 1-D wave's two modes:
//!
//! ```text
//!   s =     0.1    1      2      3      5      20     100    400
//!   θ = ½   0.998  0.816  0.577  0.426  0.667  0.980  0.999  1.000
//!   θ = 0.6 0.997  0.791  0.542  0.395  0.250  0.649  0.666  0.667
//!   θ = ¾   0.996  0.756  0.500  0.359  0.225  0.315  0.333  0.333
//!   θ = 1   0.995  0.707  0.447  0.316  0.196  0.050  0.010  0.002
//! ```
//!
//! (`s = kΔt c` is π times the wave Courant number `Δt c/h` for the grid's shortest wave.)
//! Every θ ≥ ½ is stable for every s; above ½ the stiff modes are damped. At θ = ½ the step
//! still loses `½ ∫ w G |ΔB|²` (the stress at the step's end). The coupled step takes the
//! stress at θ instead, `θ τ^{n+1} + (1 − θ) τⁿ`, which loses only the θ-method's share (see
//! `coupled`, "The stress at θ"; its long steps' limits in "Limits").
//!
//! **θ of the stress.** The momentum step generalises to
//! `ρ δ/Δt = ∇·[α τ^{n+2/3} + (1 − α) τⁿ]`, i.e.
//! `(M − θ_v Δt K_v − αθΔt² K_J) δ = Δt·vol·∇·[α τ^{n+1/3} + (1 − α) τⁿ]` (one more law
//! evaluation a step, `τ(Bⁿ)` without its tangent, where α < 1). With α = θ the step is the
//! θ-method on the pair (velocity, strain): at θ = ½ Crank–Nicolson, second order and without
//! damping (`|amplification| = 1` for the 1-D wave at every s). The split projection, though,
//! pumps energy into an undamped stiff solid (see `coupled`, "The stress at θ": the midpoint
//! stress gained 2–3 % of the map's budget at the wave cap). So a split step takes α = θ up to
//! an elastic-wave Courant number `Δt·c/h` of [`CN_WAVE_COURANT`] (1: `s ≤ π` for the
//! grid's shortest wave), α = 1 from [`DAMPED_WAVE_COURANT`] (2) on, linear in between
//! (`numerics.elastic.stress_theta` sets α outright). A smooth flow resolved in time runs well
//! below 1 (the Couette layers at 0.14 and 0.03); the stiff solids of the stability map run at
//! the cap, 4, where nothing changes. The coupled step takes α = θ always.
//!
//! # Coupling with the viscous step
//!
//! The viscous stage has already made `V^{n+1/3}` with an implicit viscous operator `K_v`
//! (θ-scheme). Where viscosity relaxes faster than a step (`ρh²/μ ≪ Δt`, e.g. the fluid beside
//! an inviscid solid in Sugiyama's Couette test), splitting the viscous and elastic solves leaves
//! the elastic increment unrelaxed: the first fluid cell is dragged with the solid at O(1) error,
//! whatever Δt. The elastic system therefore includes the implicit viscous operator,
//! `(M − θΔt K_v − (Δt²/2) K_J) δ = Δt·vol·∇·τ^{n+1/3}`: since `K_v V^{n+1/3} + K_v δ =
//! K_v V^{n+2/3}`, the viscous and elastic stages together are then exactly one coupled implicit
//! viscous–elastic step.
//!
//! # Stress-free reference
//!
//! The stage divides `w (τ(B) − τ(I))`: the law's stress minus its stress in the undeformed
//! state. The difference is isotropic — a change of pressure only, which the projection absorbs
//! (on the MAC metric, axisymmetric hoop term included, the force of `q I` is exactly the discrete
//! `∇q`) — but the rest stress jumps across the interface (`G φ^{1/2} I` for neo-Hookean,
//! 1.8e5 Pa for the silicone sphere), and fed through the implicit elastic solve it is smoothed
//! into a non-gradient field: the sphere was flung at ~10 m/s in its first step. The tangent is
//! unchanged (the reference does not depend on B).
//!
//! # The interface: the law on the solid's own B, the fraction on the stress
//!
//! A cell or corner on the interface holds solid (fraction `a`) and fluid side by side. The
//! solid part is deformed by the solid's own B; the fluid part has no deformation. So the law is
//! evaluated **only on the solid's own B** — never on a mixture with the fluid's identity, nor on
//! a B scaled by the fraction — and the fraction enters as a weight on the stress. How the two
//! phases share the load decides the weight:
//!
//! - **Normal components, at centres: in parallel.** Across an interface the normal and
//!   tangential strains along it are continuous (iso-strain), so the cell's stress is the
//!   phases' stresses weighted by their shares: the elastic part is `w (τ(B) − τ(I))` with the
//!   weight `w = φ^{1/2}`. (A volume average would weigh `φ`; efsi keeps the seed's `φ^{1/2}`,
//!   whose neo-Hookean stress `G φ^{1/2} B` is exactly the seed's `τ(B̃)`, `B̃ = φ^{1/2} B`:
//!   both are first-order consistent at an interface and agree in full cells.) The tangent is
//!   `w J(B)`: positive wherever the law's is. Evaluating the law on `B̃` instead, as the seed
//!   writes it, is right only for a law linear in B: Saint Venant–Kirchhoff on `φ^{1/2}B` has the
//!   shear stiffness `μ(2φ^{1/2} − 1)`, negative for `φ < ¼`.
//! - **Shear, at corners: in series** (see "Interface corners" below): one shear stress, the
//!   shear rate shared. The law sees the solid's own B — its normal components the
//!   **solid-weighted** average of the four cells' (each cell weighted by the PLIC volume of
//!   solid in its quarter next to the corner; cells without deformation weigh nothing), not the
//!   plain average, which mixes in the fluid's `B = I` and feeds a law that depends on `tr B` at
//!   a corner half in solid `tr B − 3 ≈ γ²/2` instead of `γ²` — and its shear stress counts with
//!   the series weight `a/(aκ)` below.
//!
//! So at any interface point the stress the stage applies is the law's stress at the solid's own
//! deformation times a documented weight (`φ^{1/2}` at centres less the rest stress, `a/(aκ)` at
//! corners), whatever the law; for neo-Hookean (τ linear in B) it is the seed's stress to
//! round-off. The strain energy is weighted alike, `∫ w W(B) dV`.
//!
//! B and its rates are transported as B (B̃ and B obey the same law because φ_s is materially
//! conserved). In pure fluid (`w = 0`) B is reset to I and its rates to zero at the start of
//! each step; cells with less than `PHI_MIN` (1e-3) of solid count as fluid.
//!
//! # Pure fluid: the identity also when the rates are taken
//!
//! The end-of-step update stretches B wherever it transports it, fluid cells near the solid
//! included (there `E = 0`: their rates were reset), and the rates `Aⁿ⁺¹ = ∇·(Vⁿ⁺¹ Bⁿ⁺¹)`
//! are taken right after, before the VOF step moves the interface and before the next
//! step's reset. A fluid cell would then hold `B = I + θΔt (L_f + L_fᵀ)`, one step of the
//! fluid's velocity gradient (`O(U/R)` around a moving body, the hoop rate `u_r/r` largest
//! beside the axis), and it reaches the solid two ways: where the flow enters the solid's
//! cells — its trailing interface — the upwind van Leer face values of `Aⁿ⁺¹` carry it in,
//! `(UΔt/h)·2θΔt D_f` a step; and a cell the solid enters at its leading interface is not
//! reset and keeps it. Either way about `2θΔt D_f` per cell the interface crosses, stored at
//! G: energy growing like `Δt²`. It was the strain a stiff solid kept in rigid motion, which
//! limited the coupled step: the stability map's sphere (G = 1e9 Pa, 8 cells per radius)
//! falling clear of the wall at 1.22 m/s held at most 2.8e-5, 1.3e-4, 2.9e-4, 1.4e-3, 7.3e-3
//! of its kinetic energy as strain with coupled steps of 4, 8, 12, 25, 50 elastic-wave Courant
//! numbers, 5e-2, 0.48, 0.55 at 100, 200, 400 (where the fall gained 1.5 %, 10 %, 18 % of its
//! energy). The update therefore resets the fluid's B to the identity before it takes the
//! rates: the same sphere now holds at most 1.9e-7, 5e-8, 2e-8, 5e-9, 1.3e-9 at 4 to 50 and
//! 5.6e-9, 3.5e-6, 3.2e-5 at 100, 200, 400 (the split step at 4: 5.3e-6 at the end of its
//! fall, now 1.3e-9). Only the rates and the cells the solid enters change: the stress and
//! the strain energy weigh the fluid by `w = 0`. Taking the rates from the solid's B extended
//! into the fluid (the reference-map technique's extrapolation) removed the strain as well,
//! but moved the soft disk in the cavity off Zhao et al.'s path (mean distance at 32² 0.0165
//! against 0.0078; with the reset 0.0076), and the rates alone extended, B kept, left 1.0e-4
//! and 2.2e-3 at 25 and 50.
//!
//! # Interface corners: the shear in series
//!
//! The shear component lives at corners, and a corner on the interface holds solid and fluid
//! side by side across the interface, where they shear **in series**: one shear stress, the
//! shear rate shared, `2D = a·2D_s + (1 − a)·2D_f`. With a Kelvin–Voigt solid
//! `τ = τ_e(B) + μ_s 2D_s` and a Newtonian fluid `τ = μ_f 2D_f`,
//!
//! ```text
//!   τ = τ_e/κ + μ_h 2D,   2D_s = (2D − (1 − a) τ_e/μ_f) / (aκ),
//!   aκ = a + μ_s (1 − a)/μ_f,   μ_h = μ_s μ_f / (a μ_f + (1 − a) μ_s)  (harmonic mean),
//! ```
//!
//! so at such a corner the law sees the solid's own B, its shear stress counts `1/κ = a/(aκ)`,
//! the viscous stage's corner viscosity is the harmonic mean (see
//! `viscous_operator::corner_viscosity`), and B₁₂ is stretched by the solid's velocity gradient — shear
//! rate `2D/(aκ)` — less a relaxation `r τ_e` (`r = (1 − a)/(μ_f aκ)`): the fluid's share of a
//! sustained shear. The solid's gradient differs from the corner's only in the derivative
//! across the interface (the velocity is continuous along it, and so are its derivatives along
//! it): with `n` the interface normal (∝ ∇φ over the four cells), the extra shear rate goes to
//! `L₁₂ = ∂u/∂y` by the share `n_y²` and to `L₂₁ = ∂v/∂x` by `n_x²` — all of it to `L₁₂` at a
//! horizontal interface, where then `Ḃ₁₂ = L₁₂ B₂₂` does not see `B₁₁` (splitting it evenly,
//! which leaves the spin unchanged, added `(s − 1) D₁₂ (B₁₁ − B₂₂)`, of order `γ²`). The cells
//! around the corner hold the same solid, so their normal components are stretched by the same
//! solid gradient: `Ḃ₁₁ = 2 L₁₂ B₁₂` and `Ḃ₂₂ = 2 L₂₁ B₁₂` average the corners' solid gradients,
//! relaxation included (explicit, at Bⁿ, as much of it as the corner's implicit step applies,
//! × q: the full explicit rate blew the sphere in air up within 1 ms). With the corner's mixed
//! gradient instead, the last solid cell's `B₁₁` lagged, and with it the `tr B` a law sees at the
//! interface corner: the Mooney–Rivlin Couette case (τ = 2c₁γ + 4c₃γ³) at 64 cells erred by
//! 5.2e-3, against 2.1e-3. The relaxation is implicit (a θ_r-step, linearised with the
//! law's `∂τ₁₂/∂B₁₂` at Bⁿ), which makes `B₁₂(V)` still affine in V: the step's
//! `B₁₂ = q (Bⁿ + E' + (Δt/2) H(V; Bⁿ))` with `q = 1/(1 + θ_r z)`, `z = Δt r b̄ J₁₂₁₂`, and `E'`
//! the explicit part less the relaxation's linearisation remainder (`Deformation::relax` holds
//! q). `θ_r = ½ + ½ z/(1 + z)`: trapezoidal where the relaxation is slow over a step
//! (`θ_r − ½ = O(Δt)`, so second order in time: a backward-Euler relaxation made the Couette
//! layer's interface first order in time), backward Euler where it is stiff (a solid in air,
//! `z ≫ 1`), and monotone for every z (the amplification `(1 − (1 − θ_r) z)/(1 + θ_r z)` lies
//! in `(0, 1)`).
//!
//! **The corner's solid fraction** `a` is the solid volume of the four quarter cells around the
//! corner over theirs, each quarter's share cut by its cell's PLIC line (Youngs normal, planar
//! fit, as the VOF step reconstructs); uncut cells count their φ. The mean of the four cells' φ
//! instead spreads a cut cell's solid evenly over its four corners: at a strongly sheared
//! solid–air interface it gave corners whose quarters hold no solid a series stress `1/κ ≈ a`
//! and a solid shear rate, and the sphere of the impact case grew a one-cell ledge at its
//! equator after the rebound that tore off (2.9 % of its volume at 15 cells per radius). A
//! corner whose quarters hold no solid carries no elastic shear (`a = 0`: `1/κ = 0`).
//!
//! A parallel (arithmetic) mixture there — the seed's `φ^{1/2}`-weighted stress beside the
//! averaged viscosity — lets the solid's elasticity and the fluid's viscosity both act over the
//! whole corner: an O(1) error in the interface shear, first order overall, and the dominant
//! error of Sugiyama's Couette test (at 64 cells the profile error fell from 0.0179 to 0.0090
//! in series, and the error at the grid points is 0.0015). For a solid in air (`μ_f` small) the
//! relaxation is fast: the interface corner carries little shear and the solid slides past the
//! air instead of dragging an O(1) spurious shear strain, which had flung the sphere of the
//! impact case.
//!
//! # Space discretisation
//!
//! Staggered like the viscous stress: `B̃₁₁, B̃₂₂, B̃₃₃` and `τ₁₁, τ₂₂, τ₃₃` at cell centres,
//! `B̃₁₂`, `τ₁₂` at corners, so `∂τ₁₂/∂y` on a u-face is a compact difference. `L₁₁, L₂₂, L₃₃`
//! live at centres, `L₁₂ = ∂u/∂y`, `L₂₁ = ∂v/∂x` at corners; a component needed at the other
//! location is the average of its four neighbours. The law is evaluated in two batches (centres
//! and corners), with the missing components averaged. Advection `∇·(V B̃)` is conservative with
//! van Leer limited upwind face values, as the momentum advection.
//!
//! # Solve
//!
//! BiCGSTAB, right-preconditioned (scene `numerics.elastic.preconditioner`):
//! - `Multigrid`: since the implicit tangent acts like a viscosity `G_eff Δt/2`, the
//!   SPD approximation `M − vol·∇·(2ηD)` with `η = θΔt μ + (Δt²/2) G_eff` (`Kernels::stiffness`:
//!   `G_eff` from the tangent's diagonal and B̃, and at the interface corners the series
//!   factors) is preconditioned by one multigrid V-cycle on each of its u–u and v–v blocks
//!   (`block_multigrid`). Jacobi's iteration count grows with the elastic wave's Courant
//!   number `Δt√(G/ρ)/h`, the block multigrid's hardly.
//! - `Jacobi`: a bound of the diagonal (the mass plus the stiffness over `h²`).
//! - `Auto` (the default): `Multigrid`, but `Jacobi` in scenes with a periodic boundary — the
//!   red–black smoother keeps a flow uniform along the periodic direction uniform only to the
//!   tolerance (a 1e-12 cross-flow leaked 2.5e-13 of solid fraction into the fluid of the
//!   periodic Couette layer), Jacobi exactly.
//!
//! The increment's stress `J : (w ΔB)` vanishes outside the solid, so the operator computes
//! gradients, stretching and tangent only over the solid's bounding box (plus the ring the
//! stencils read) and adds its force only to the faces next to it: the cost of the elastic part
//! follows the solid's size, not the grid's. The law's batches hold the same window's centres
//! and corners, and B is transported only within a few cells of any material, where it can
//! reach the solid within a step (`Kernels::near_c`); beyond, it stays the identity. The viscous part `θΔt K_v` is applied over the
//! whole grid by the one viscous operator (`viscous_operator`, coefficients set once per step),
//! the block multigrid preconditioner takes its blocks from the same operator with the
//! effective viscosities `η`. Its V-cycles run on a window around the solid only, grown by the
//! distance over which the surrounding fluid's response decays by 1e-4 (`block_multigrid`,
//! "Window"), with the Jacobi diagonal elsewhere: on the sphere impact the split step's elastic
//! stage is ≈ 23 % cheaper at the same iterations, the coupled step's ≈ 9 % (10.6 FGMRES
//! iterations a step against 10.4). Loops over rows
//! and BiCGSTAB's reductions run in parallel with fixed results: the iterates are bit-identical
//! on any number of threads.
//!
//! # Stability
//!
//! Unconditionally stable in the elastic wave speed for the neo-Hookean law at moderate
//! deformation (the implicit part dominates); the explicit AB2 advection follows the flow's CFL.

use crate::block_multigrid::ViscousBlocks;
use crate::faces::UnknownFaces;
use crate::viscous_operator::Coefficients;
use efsi_core::scene::{Boundary, Options, OptionsDecl, Side};
use efsi_core::{
    BoundarySet, Field, FieldId, G, Grid, Phase, Scene, Stage, StageError, StagePlugin,
};
use efsi_laws_host::{Sym, Tangent};
use efsi_linalg::BiCgStab;

mod choice;
mod coupled;
mod deformation;
mod energy;
mod interface;
mod law;
mod limits;
mod options;
mod outputs;
mod resource;
mod rows;
mod solve;
mod stress;
#[cfg(test)]
mod tests;
mod transport;

pub(crate) use choice::{CoupledStep, coupling, may_couple};
use choice::{StepScheme, coupled_step};
use deformation::DeformationStage;
pub use law::resolve_law;
use law::shared_law;
pub use limits::MIN_CELLS_ACROSS;
use limits::shared_wave_limits;
pub use options::{
    AUTO_COUPLED_GAIN, AUTO_STRAIN_SHARE, AUTO_WALL_CELLS, CN_WAVE_COURANT, DAMPED_WAVE_COURANT,
    DEFAULT_AUTO_COUPLED_WAVE_COURANT, DEFAULT_COUPLED_WAVE_COURANT, ElasticCoupling,
    ElasticOptions, ElasticPreconditioner, MAX_COUPLED_WAVE_COURANT, MAX_WAVE_COURANT,
};
pub use resource::Deformation;
use rows::{PAR_POINTS, Window, at, rows1, rows2, rows3};
use solve::{ElasticOperator, ElasticStage, Scratch};

/// The field the elastic stages own: the solid's tensor B and its history ([`Deformation`]).
pub const B: FieldId = FieldId::Stage("B");

/// Whether a checked scene (`options`) has an elastic solid (a solid with a constitutive law).
pub(crate) fn law_needed(options: &Options) -> bool {
    crate::solid::solid(options).is_ok_and(|s| s.law.is_some())
}

/// The fluid's and the solid's viscosities, for the interface corners.
fn viscosities(scene: &Scene, options: &Options) -> (f64, f64) {
    let mu_f = scene.fluid.viscosity;
    let mu_s = crate::solid::solid(options).map_or(mu_f, |s| s.viscosity(&scene.fluid));
    (mu_f, mu_s)
}

/// The elastic stage plugin (phase Elastic).
pub struct Elastic;

/// The end-of-step B̃ update (phase Projection, after the projection).
pub struct DeformationUpdate;

impl StagePlugin for Elastic {
    fn name(&self) -> &'static str {
        "elastic"
    }
    fn phase(&self) -> Phase {
        Phase::Elastic
    }
    fn reads(&self) -> &'static [FieldId] {
        &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::Density,
            FieldId::Viscosity,
            FieldId::SolidFraction,
            B,
        ]
    }
    fn writes(&self) -> &'static [FieldId] {
        // The pressure only in the coupled step (`coupled`), which leaves its pressure for
        // the projection stage to complete.
        &[FieldId::VelocityX, FieldId::VelocityY, B, FieldId::Pressure]
    }
    fn needed(&self, _scene: &Scene, options: &Options) -> bool {
        law_needed(options)
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<ElasticOptions>())
    }
    fn outputs(&self) -> &'static [efsi_core::OutputDecl] {
        outputs::OUTPUTS
    }
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let law = shared_law(scene, options, shared)?;
        let (mu_f, mu_s) = viscosities(scene, options);
        let k = Kernels::new(grid, bc, mu_f, mu_s);
        let n = k.faces.len();
        let o: &ElasticOptions = options.section()?;
        let couples = may_couple(options);
        let limits = shared_wave_limits(scene, options, grid, law.as_ref(), shared)?;
        let schemes = [false, true].map(|coupled| StepScheme {
            theta: o.stretch_theta(coupled),
            // The coupled step's momentum takes the stress at its stretching's θ (see `coupled`,
            // "The stress at θ"); the split step's weight depends on the step's elastic-wave
            // Courant number, set per step (`ElasticStage::set_scheme`).
            alpha: if coupled { o.stretch_theta(true) } else { 1.0 },
            preconditioner: match o.preconditioner {
                // The coupled step keeps the multigrid: with Jacobi for its velocity block
                // its FGMRES stagnates (the shear rectangle at 96 × 24: 1.2e-9 of the scale
                // after 500 iterations).
                ElasticPreconditioner::Auto
                    if !coupled
                        && efsi_core::scene::Side::ALL.iter().any(|&s| {
                            matches!(
                                scene.boundaries.get(s),
                                efsi_core::scene::Boundary::Periodic
                            )
                        }) =>
                {
                    ElasticPreconditioner::Jacobi
                }
                ElasticPreconditioner::Auto => ElasticPreconditioner::Multigrid,
                p => p,
            },
        });
        Ok(Box::new(ElasticStage {
            mode: coupling(options),
            split_dt: limits.split,
            wave_step: limits.wave_step,
            options: o.clone(),
            step_flag: {
                // Until the first step says otherwise (the projection of the initial velocity).
                let flag = CoupledStep::shared(shared);
                flag.set(coupling(options) == ElasticCoupling::Coupled);
                flag
            },
            law,
            tau: std::array::from_fn(|_| Field::zeros(grid)),
            tau_n: std::array::from_fn(|_| Field::zeros(grid)),
            op: ElasticOperator {
                k,
                db: std::array::from_fn(|_| Field::zeros(grid)),
                mass: vec![0.0; n],
                c: 0.0,
                theta_dt: 0.0,
                mu: Field::zeros(grid),
                mu_corner: Field::zeros(grid),
                viscous: Coefficients::new(grid, UnknownFaces::new(grid, bc)),
                dm: vec![0.0; n],
            },
            scheme: schemes[0],
            theta: if crate::viscous::Viscous.needed(scene, options) {
                options
                    .section_or_default::<crate::viscous::ViscousOptions>(scene.numerics.preset)
                    .theta
            } else {
                0.0
            },
            rhs: vec![0.0; n],
            delta: vec![0.0; n],
            diag: vec![0.0; n],
            solver: BiCgStab::new(n),
            tol: o.tolerance,
            max_iter: o.max_iterations,
            implicit: o.implicit,
            schemes,
            blocks: ViscousBlocks::new(grid, bc),
            eta: Field::zeros(grid),
            eta_k: Field::zeros(grid),
            eta_coefficients: Coefficients::new(grid, UnknownFaces::new(grid, bc)),
            eta_dm: vec![0.0; n],
            eta_diag: vec![0.0; n],
            scratch: Scratch {
                xu: Field::zeros(grid),
                xv: Field::zeros(grid),
                dtau: std::array::from_fn(|_| Field::zeros(grid)),
            },
            coupling: if couples {
                let proj: crate::projection::ProjectionOptions =
                    options.section_or_default(scene.numerics.preset);
                Some(coupled::Coupling::new(
                    grid,
                    bc,
                    n,
                    o,
                    proj.tolerance_in(scene),
                ))
            } else {
                None
            },
        }))
    }
}

impl StagePlugin for DeformationUpdate {
    fn name(&self) -> &'static str {
        "deformation"
    }
    fn phase(&self) -> Phase {
        Phase::Projection
    }
    fn reads(&self) -> &'static [FieldId] {
        &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::SolidFraction,
            B,
        ]
    }
    fn writes(&self) -> &'static [FieldId] {
        &[B]
    }
    fn after(&self) -> &'static [&'static str] {
        &["projection"]
    }
    fn limit_depends_on(&self) -> &'static str {
        "numerics.elastic.wave_courant (coupled_wave_courant with the coupled step) and the solid's stiffness: the elastic wave speed"
    }
    fn needed(&self, _scene: &Scene, options: &Options) -> bool {
        law_needed(options)
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<ElasticOptions>())
    }
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let (mu_f, mu_s) = viscosities(scene, options);
        let law = shared_law(scene, options, shared)?;
        let o: &ElasticOptions = options.section()?;
        let limits = shared_wave_limits(scene, options, grid, law.as_ref(), shared)?;
        Ok(Box::new(DeformationStage {
            law,
            k: Kernels::new(grid, bc, mu_f, mu_s),
            mode: coupling(options),
            limits,
            walls: efsi_core::scene::Side::ALL.map(|side| {
                matches!(
                    scene.boundaries.get(side),
                    efsi_core::scene::Boundary::NoSlip
                        | efsi_core::scene::Boundary::MovingWall { .. }
                        | efsi_core::scene::Boundary::FreeSlip
                )
            }),
            thetas: [o.stretch_theta(false), o.stretch_theta(true)],
            step_flag: CoupledStep::shared(shared),
            first: std::array::from_fn(|_| Field::zeros(grid)),
        }))
    }
}

/// Velocity gradients, stretching, advection, law batches and stress divergence on the
/// staggered layout.
struct Kernels {
    grid: Grid,
    bc: BoundarySet,
    /// The unknown faces and their compact order.
    faces: UnknownFaces,
    /// L₁₁, L₂₂, L₃₃ at centres.
    lc: [Field; 3],
    /// The solid's L₁₂, L₂₁ at corners (the shear rate's interface share included: see
    /// [`Kernels::gradient_in`]).
    lk: [Field; 2],
    /// `φ^{1/2}` at centres and its four-cell average at corners (zero exactly where the
    /// corner has no solid).
    w: Field,
    wc: Field,
    /// Interface shear in series (see "Interface corners" in the module docs): the corner's
    /// B̃ weight `w_k` (1 with any solid, else 0), its solid shear-rate factor `s = 1/(aκ)`,
    /// stress factor `1/κ` and relaxation coefficient `r = (1 − a)/(μ_f a κ)`.
    wk: Field,
    sf: Field,
    ks: Field,
    rc: Field,
    /// Per centre, the solid fraction of each quarter of the cell by its PLIC line (lower-left,
    /// lower-right, upper-left, upper-right; `φ` itself in uncut cells and beyond the batch).
    quarter: [Field; 4],
    /// Per corner, the weights of its four cells (lower-left, lower-right, upper-left,
    /// upper-right of the corner) in its normal components of B: each cell's solid quarter
    /// next to the corner, over their sum (cells without deformation, `w = 0`, weigh nothing).
    kwt: [Field; 4],
    /// Per corner, the share `n_y²` of the interface's unit normal (from the four cells' φ;
    /// ½ where φ is uniform): the part of the solid's extra shear rate that goes to `L₁₂`, the
    /// rest going to `L₂₁` (see "Interface corners").
    ny2: Field,
    /// The fluid's and the solid's viscosities (scene values).
    mu_f: f64,
    mu_s: f64,
    /// The centres holding solid (`w > 0`, within `[−1, nx] × [−1, ny]`) and the corners
    /// touching them (the only ones with `w_k > 0`), set by [`Kernels::set_weights`]: outside
    /// them the tangent's stress increment vanishes (it is weighted by `w`, `w_k`), so the
    /// elastic operator skips them.
    solid_c: Window,
    solid_k: Window,
    /// The centres within [`NEAR`] cells of any material (`φ > 0`, flotsam included) and
    /// their corners, set by [`Kernels::set_weights`]: the deformation is transported there
    /// only. Elsewhere B stays the identity and its rates zero ([`Kernels::reset_fluid`]):
    /// a cell becomes solid only from a neighbour's material (the VOF step moves less than a
    /// cell per step), and its B and rates read B at most three cells beyond it (the
    /// advection's van Leer stencil), so the solid's deformation is the same as if B were
    /// transported everywhere.
    near_c: Window,
    near_k: Window,
    /// Work space of [`Kernels::strain_energy`]: per solid cell, its index, weight, principal
    /// axes (cos, sin), the logarithms of the principal stretches and its volume.
    energy_cells: Vec<EnergyCell>,
    /// Law batches, sized for every centre `[−1, nx] × [−1, ny]` and corner `[0, nx] × [0, ny]`:
    /// the centres of `solid_c` and the corners of `solid_k` ([`Kernels::ci`], `ki`).
    cb: Vec<Sym>,
    ct: Vec<Sym>,
    cj: Vec<Tangent>,
    kb: Vec<Sym>,
    kt: Vec<Sym>,
    kj: Vec<Tangent>,
}

/// Cells with less solid than this carry no deformation (B = I, no stress): VOF flotsam and
/// slivers of an interface whose B the mixed-cell velocity gradient spoils. Their stress,
/// weighted by `φ^{1/2}`, would act on a face whose mass is the fluid's (`φρ_s ≪ ρ_f` at a
/// density ratio of 1000), which flung air at tens of m/s as a sphere left the substrate.
const PHI_MIN: f64 = 1e-3;

/// How many cells beyond any material the deformation is transported ([`Kernels::near_c`]):
/// one cell the material may reach in a step, three more its B and rates read.
const NEAR: isize = 4;

/// See [`Kernels::strain_energy`].
type EnergyCell = (usize, f64, f64, f64, f64, f64, f64, f64);

#[inline(always)]
fn avg4(f: &[f64], a: usize, b: usize, c: usize, d: usize) -> f64 {
    0.25 * (f[a] + f[b] + f[c] + f[d])
}

impl Kernels {
    fn new(grid: &Grid, bc: &BoundarySet, mu_f: f64, mu_s: f64) -> Self {
        let nc = (grid.nx + 2) * (grid.ny + 2);
        let nk = (grid.nx + 1) * (grid.ny + 1);
        Kernels {
            grid: grid.clone(),
            bc: bc.clone(),
            faces: UnknownFaces::new(grid, bc),
            lc: std::array::from_fn(|_| Field::zeros(grid)),
            lk: std::array::from_fn(|_| Field::zeros(grid)),
            w: Field::zeros(grid),
            wc: Field::zeros(grid),
            wk: Field::zeros(grid),
            sf: Field::zeros(grid),
            ks: Field::zeros(grid),
            rc: Field::zeros(grid),
            quarter: std::array::from_fn(|_| Field::zeros(grid)),
            kwt: std::array::from_fn(|_| Field::zeros(grid)),
            ny2: Field::zeros(grid),
            mu_f,
            mu_s,
            solid_c: Window::EMPTY,
            solid_k: Window::EMPTY,
            near_c: Window::EMPTY,
            near_k: Window::EMPTY,
            energy_cells: Vec::new(),
            cb: vec![[0.0; 4]; nc],
            ct: vec![[0.0; 4]; nc],
            cj: vec![[0.0; 16]; nc],
            kb: vec![[0.0; 4]; nk],
            kt: vec![[0.0; 4]; nk],
            kj: vec![[0.0; 16]; nk],
        }
    }

    fn nxy(&self) -> (isize, isize) {
        (self.grid.nx as isize, self.grid.ny as isize)
    }

    /// The centres and corners whose gradients [`Kernels::stretch_in`] reads at the centres
    /// `c` and their corners: one centre more all round (within the batch), and the corners of
    /// every centre (ghost corners included: the axis's odd B̃₁₂ is not zero there).
    fn gradient_windows(&self, c: Window) -> (Window, Window) {
        let (nx, ny) = self.nxy();
        if c.i0 > c.i1 {
            return (Window::EMPTY, Window::EMPTY);
        }
        (
            Window::new(
                (c.i0 - 1).max(-1),
                (c.i1 + 1).min(nx),
                (c.j0 - 1).max(-1),
                (c.j1 + 1).min(ny),
            ),
            Window::new(c.i0, c.i1 + 1, c.j0, c.j1 + 1),
        )
    }

    /// Batch index of centre `(i, j)` of the solid's window [`Kernels::solid_c`] (the law
    /// batches hold the window's points, row by row).
    #[inline(always)]
    fn ci(&self, i: isize, j: isize) -> usize {
        let c = self.solid_c;
        debug_assert!(c.contains(i, j), "centre ({i}, {j}) outside {c:?}");
        ((j - c.j0) * (c.i1 - c.i0 + 1) + i - c.i0) as usize
    }

    /// Batch index of corner `(i, j)` of the solid's corners [`Kernels::solid_k`].
    #[inline(always)]
    fn ki(&self, i: isize, j: isize) -> usize {
        let c = self.solid_k;
        debug_assert!(c.contains(i, j), "corner ({i}, {j}) outside {c:?}");
        ((j - c.j0) * (c.i1 - c.i0 + 1) + i - c.i0) as usize
    }

    /// The solid-weighted average at corner `k` (linear index) of a centre field `f`: the
    /// interface-consistent value of a normal component there (see "Interface corners").
    #[inline(always)]
    fn kavg(&self, f: &[f64], k: usize, s: usize) -> f64 {
        let [w0, w1, w2, w3] = [
            self.kwt[0].data()[k],
            self.kwt[1].data()[k],
            self.kwt[2].data()[k],
            self.kwt[3].data()[k],
        ];
        w0 * f[k - s - 1] + w1 * f[k - s] + w2 * f[k - 1] + w3 * f[k]
    }

    /// A law's error with the cell it names (an entry of the centre batch, or of the corner
    /// batch if `corner`) turned into the grid's cell (or corner) index and position.
    fn locate(&self, e: efsi_laws_host::LawError, corner: bool) -> String {
        let Some(q) = e.cell else {
            return e.to_string();
        };
        let g = &self.grid;
        let text = efsi_laws_host::LawError { cell: None, ..e }.to_string();
        let c = if corner { self.solid_k } else { self.solid_c };
        let w = (c.i1 - c.i0 + 1).max(1) as usize;
        let (i, j) = (c.i0 + (q % w) as isize, c.j0 + (q / w) as isize);
        if corner {
            format!(
                "{text} at corner (i, j) = ({i}, {j}), (x, y) = ({:.6e}, {:.6e})",
                g.xf(i),
                g.yf(j)
            )
        } else {
            format!(
                "{text} in cell (i, j) = ({i}, {j}), centre (x, y) = ({:.6e}, {:.6e})",
                g.xc(i),
                g.yc(j)
            )
        }
    }

    /// Fill the ghosts of a staggered tensor.
    fn fill_ghosts(&self, t: &mut [Field; 4]) {
        for f in t.iter_mut().take(3) {
            self.bc.fill_scalar(&self.grid, f, false);
        }
        fill_corner(&self.bc, &self.grid, &mut t[3], true);
    }
}

/// Fill the ghosts of a corner-staggered field (B̃₁₂, at the cell corners: a staggering of
/// this stage's, which the core's boundary conditions do not know): wrap at periodic sides,
/// even reflection about the boundary line elsewhere, except at the axis where a shear
/// component is odd in r — zero on the axis — when `odd_at_axis`.
fn fill_corner(bc: &BoundarySet, grid: &Grid, f: &mut Field, odd_at_axis: bool) {
    let (nx, ny) = (grid.nx as isize, grid.ny as isize);
    for (axis, n, m, lo_side) in [(0, nx, ny, Side::XMin), (1, ny, nx, Side::YMin)] {
        let at = |a: isize, b: isize| if axis == 0 { (a, b) } else { (b, a) };
        let periodic = *bc.get(lo_side) == Boundary::Periodic;
        let sign = if odd_at_axis && *bc.get(lo_side) == Boundary::Axis {
            -1.0
        } else {
            1.0
        };
        for b in -G..(m + 1 + G) {
            if periodic {
                f[at(n, b)] = f[at(0, b)];
                for g in 1..=G {
                    f[at(-g, b)] = f[at(n - g, b)];
                    f[at(n + g, b)] = f[at(g, b)];
                }
                continue;
            }
            if sign < 0.0 {
                f[at(0, b)] = 0.0;
            }
            for g in 1..=G {
                f[at(-g, b)] = sign * f[at(g, b)];
                f[at(n + g, b)] = f[at(n - g, b)];
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
