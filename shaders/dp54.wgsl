// Dormand-Prince 5(4)'s coefficients and step-size controller, shared by the DP54 kernels
// (flip_adaptive.wgsl, lyapunov.wgsl's adaptive tangent); src/cpu/adaptive.rs `DP54` holds
// the same tableau as data.

// Dormand & Prince (1980): the stages' weights (Hairer, Norsett & Wanner, table 5.2) ...
const A21 = 0.2;
const A31 = 3.0 / 40.0;
const A32 = 9.0 / 40.0;
const A41 = 44.0 / 45.0;
const A42 = -56.0 / 15.0;
const A43 = 32.0 / 9.0;
const A51 = 19372.0 / 6561.0;
const A52 = -25360.0 / 2187.0;
const A53 = 64448.0 / 6561.0;
const A54 = -212.0 / 729.0;
const A61 = 9017.0 / 3168.0;
const A62 = -355.0 / 33.0;
const A63 = 46732.0 / 5247.0;
const A64 = 49.0 / 176.0;
const A65 = -5103.0 / 18656.0;
// ... the fifth-order solution's (its last stage, at that solution, starts the next step) ...
const B1 = 35.0 / 384.0;
const B3 = 500.0 / 1113.0;
const B4 = 125.0 / 192.0;
const B5 = -2187.0 / 6784.0;
const B6 = 11.0 / 84.0;
// ... the error estimate's (fifth minus embedded fourth order) ...
const E1 = 71.0 / 57600.0;
const E3 = -71.0 / 16695.0;
const E4 = 71.0 / 1920.0;
const E5 = -17253.0 / 339200.0;
const E6 = 22.0 / 525.0;
const E7 = -1.0 / 40.0;
// ... and the dense output's (dopri5.f).
const D1 = -12715105075.0 / 11282082432.0;
const D3 = 87487479700.0 / 32700410799.0;
const D4 = -10690763975.0 / 1880347072.0;
const D5 = 701980252875.0 / 199316789632.0;
const D6 = -1453857185.0 / 822651844.0;
const D7 = 69997945.0 / 29380423.0;

// The step-size controller (src/cpu/adaptive.rs SAFETY, SHRINK, GROW).
const SAFETY = 0.9;
const SHRINK = 0.2;
const GROW = 5.0;
