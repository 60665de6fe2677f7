// Dormand-Prince 5(4)'s coefficients and step-size controller, shared by the DP54 kernels
// (flip_adaptive.wgsl, lyapunov.wgsl's adaptive tangent). The coefficients are written in by
// src/gpu/shaders.rs from src/tableau.rs `DP54`, the tableau the CPU twins loop over: the
// stages' weights Aij, the fifth-order solution's Bj (its last stage, at that solution,
// starts the next step), the error estimate's Ej (fifth minus embedded fourth order) and the
// dense output's Dj (dopri5.f), nonzero ones only.

//{{COEFFICIENTS}}

// The most step attempts a pixel takes through its renormalisation windows (2^24: a count an
// f32 still holds exactly), after which it stalls (adaptive_windows.wgsl).
const MAX_WINDOW_ATTEMPTS: real = 16777216.0;

// The step-size controller (src/cpu/adaptive.rs SAFETY, SHRINK, GROW).
const SAFETY = 0.9;
const SHRINK = 0.2;
const GROW = 5.0;
