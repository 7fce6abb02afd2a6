/*
 * softclose's stroke kernel: closing strokes of the reduced lid equation, a batch at a time.
 *
 * The equation of motion on the lid's angle th (SPEC §3):
 *     M(th) th'' + 1/2 M'(th) th'^2 = -dV/dth - (damping) th' + (friction)
 * with V the potential of gravity and of every spring element and the damping of every
 * viscous element; each element's law is stated once, in THE MACHINE ELEMENTS below, on the
 * columns of a table of cubic Hermite pieces (the closure's coefficients M, dM, Vg, dVg,
 * l, dl, dd, tau, and the coordinate table's element columns) built in Python from the
 * CasADi model and its exact derivatives (softclose/simulation/kernel/table.py). One
 * fixed-step method per call, given by a Butcher tableau: kind 0 explicit Runge-Kutta,
 * kind 1 implicit Runge-Kutta (Newton), kind 2 symplectic Euler (velocity first).
 *
 * Events -- the closing, a turning point, the peak tip speed, a rest of dry friction, a
 * crossing of the end damper's angle -- are located by a last step of solved length (Newton
 * on the step length), so they are as accurate as the method itself; nothing is
 * integrated past an event, and a law that changes at an event is switched there, never
 * smoothed.
 *
 * A design row is the elements' parameters in the registry's order, then e_tol, then
 * optionally m_lid (kg; NaN: the table's own mass m0) and the row's own attachment points
 * (PER-ROW ATTACHMENT POINTS below). M, dM, Vg and dVg are affine in the lid's mass: a row's
 * coefficients are c(m0) + (m_lid - m0) dc/dm from a second table, never read at m0.
 * The layout of rows, tables and outputs is checked against the Python side when the
 * library is loaded (sc_layout; softclose/simulation/kernel/layout.py).
 *
 * EARLY EXIT. A stroke that can no longer close and whose metrics can no longer change is
 * stopped before t_max, exactly: the energy argument, its margin for a fixed-step method's
 * energy error, and what it assumes are stated in the documentation (docs/kernel.md, "Early
 * exit"). In the code: lane_after_step and after_steps_vec. A row with a spring of a kind
 * outside its valid range at every angle of the stroke is not integrated at all
 * (lane_invalid_throughout). Why a lid stays open is recorded as stop_reason: 1 trapped
 * behind a barrier (stop_theta its top), 2 held open at the bottom of a well (stop_theta the
 * stable equilibrium), 3 held by friction (stop_theta where it came to rest).
 *
 * SPEED. Several strokes ("lanes") advance in lockstep; with AVX2 (chosen at run time) the
 * lanes are SIMD vectors, and every coefficient of a cell comes from one Horner evaluation
 * of its row of pieces -- the same IEEE operations, in the same order, as the scalar code,
 * so both paths give the same numbers bit for bit (no FMA contraction). The common case of
 * the bookkeeping after a step is done with vector compares and blends (after_steps_vec); a
 * lane that needs more runs the scalar lane_after_step.
 *
 * No Python API is used by the solver; the module init only lets setuptools build it.
 */
#include <Python.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "_layout.h" /* the layout: generated from the element registry */

/* the coordinate table (the element columns of the torsion spring and the rotary damper at
 * their pivots, tabulated when a row needs them): a row of NX values per power; which
 * element's column is which: THE MACHINE ELEMENTS */
#define SMAX 4

/* the outputs per design: their enum (O_*) is in _layout.h; O_STOP_REASON is why a lid
 * stays open (R_* below), O_STOP_THETA the barrier top, the equilibrium or the angle where
 * friction held it, O_STOP_TIME when integration stopped (event, early exit, t_max,
 * failure), O_ENGAGE_TIME / O_ENGAGE_THETA_DOT the end damper's first engagement moving
 * down (0 when released below its angle; NaN: never, or no end damper) */
/* status codes */
enum { S_CLOSED = 0, S_OPEN = 1, S_UNSTABLE = 2, S_RANGE = 3, S_NONFINITE = 4, S_NEWTON = 5 };
/* stop reasons */
enum { R_NONE = 0, R_BARRIER = 1, R_HELD = 2, R_STUCK = 3 };

/* The table, power-major: cell i holds 4 rows (powers s^0..s^3) of the NC coefficients. */
typedef struct {
    const double *cc;  /* ncell * 4 * NC cubic coefficients in the local variable s in [0, 1] */
    const double *dcc; /* the same layout: their derivative w.r.t. the lid mass (0 for l, dl,
                        * dd, tau), or NULL */
    const double *rng; /* ncell * NRNG: ranges of some pieces over each whole cell (or NULL) */
    const double *xcc; /* ncell * 4 * NX: the element columns' pieces (X_*), or NULL */
    const double *pcc; /* ncell * 4 * NPOSE: the pose pieces (PER-ROW ATTACHMENT POINTS), or
                        * NULL */
    double pA1, pA2;   /* bounds of |A'| and |A''| over the table (with pcc) */
    const int *crit;   /* the cells where l' may vanish (R_LCRIT), ascending (with rng) */
    int rot_pivot;     /* the rotary damper acts at a pivot (its psi'^2 in xcc), not the lid */
    int ncrit;
    int ncell;
    double lo, h, inv_h, m0;
} Table;
/* per cell, at the table's mass: ranges over s in [0, 1] of tau, M, Vg, l, dVg, dl (lo, hi
 * each, widened for rounding), then Vg, l, tau, M at s = 1/2, then 1 if l' may vanish in
 * the cell (a root of its derivative within 1e-9 of [0, 1]), else 0 */
enum { R_TAU = 0, R_M = 2, R_VG = 4, R_L = 6, R_DVG = 8, R_DL = 10, R_MID = 12, R_LCRIT = 16,
       NRNG = 18 };
#define CQ(base, i, e, j) ((base)[((size_t)(i) * 4 + (e)) * NC + (j)])
/* the pose table's columns (PER-ROW ATTACHMENT POINTS): the crank pin A, its slope A', cos
 * and sin of theta; NPOSE per power (two vectors of four), the last two zero */
/* (P_*, NPOSE: _layout.h) */
#define XQ(base, i, e, j) ((base)[((size_t)(i) * 4 + (e)) * NX + (j)])

/* lanes of the stroke loop are advanced as NG SIMD vectors of VW (see the stroke loop) */
#ifndef NG
#define NG 2
#endif
#define VW 4
#define LANES (NG * VW)
typedef double v4 __attribute__((vector_size(VW * sizeof(double))));
typedef long long v4l __attribute__((vector_size(VW * sizeof(long long))));
typedef int v4i __attribute__((vector_size(VW * sizeof(int))));
#define ALWAYS static inline __attribute__((always_inline))
ALWAYS v4 ld4(const double *a) { v4 v; memcpy(&v, a, sizeof v); return v; }
ALWAYS v4 abs4(v4 x)
{
    v4l mask = {0x7fffffffffffffffLL, 0x7fffffffffffffffLL, 0x7fffffffffffffffLL,
                0x7fffffffffffffffLL};
    return (v4)((v4l)x & mask);
}

ALWAYS v4 sel4(v4l m, v4 x, v4 y) { return (v4)((m & (v4l)x) | (~m & (v4l)y)); } /* m ? x : y */
#define MIN2(a, b) ((a) < (b) ? (a) : (b))
#define MAX2(a, b) ((a) > (b) ? (a) : (b))
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi" /* v4 never crosses a call: always inlined */
#endif

typedef struct {
    int kind, s;
    double A[SMAX][SMAX], b[SMAX], c[SMAX];
} Method;

/* ===== THE MACHINE ELEMENTS: every force law of the kernel, stated once ====================
 * The laws of softclose/model/elements (the registry), on the tabulated columns of each
 * element's coordinate q(theta) (its q, q' = dq/dtheta, or q'^2). A conservative element has a
 * potential V(q) and a tension T(q) = dV/dq, and adds T q' to the slope dV/dtheta; a damper
 * has a viscous coefficient B and adds B q'^2 to the damping on theta'. With them
 *     M th'' = -(slope) - 1/2 M' th'^2 - (damping) th',     E = M th'^2 / 2 + V,
 * and dE/dt = -(damping) th'^2 <= 0, which the early exit relies on (dampers only dissipate).
 *
 *   element   coordinate q       columns          law
 *   gravity   its potential      Vg, dVg (+ mass) V = q, T = 1
 *   spring    |D - E|            l, dl            V = k (q - l0)^2 / 2 + F q, T = F + k (q - l0)
 *                                                (F = s F0: its kind's sign times its preload)
 *                                                + a gas strut's V = G u psi(b u), T = G / (1 +
 *                                                b u), u = q - l0 (G = -F1, b = (1 - 1/K)/s;
 *                                                k = F = 0 for a strut, G = b = 0 for a coil)
 *   torsion   psi at its pivot   psi, dpsi (x)    V = k_t (q - psi0)^2 / 2, T = k_t (q - psi0)
 *   dashpot   |C - O|            dd = q'^2        B = c
 *   rotary    psi at its pivot   dpr2 = q'^2 (x)  B = c_rot (at the lid, q' = 1: no column)
 *   end       theta              (q' = 1)         B = c_e while the lane is engaged (below the
 *   damper                                        engagement angle theta_e), else 0: a state
 *                                                 of the lane, switched at each crossing of
 *                                                 theta_e, located as an event to the method's
 *                                                 order (lane_engage); engaged from the release
 *                                                 when theta0 < theta_e, never when theta_e <=
 *                                                 theta_closed
 *   (with one_way, the dampers act only while the lid closes: their damping is 0 for th' > 0)
 *   friction  theta              (q' = 1)         a moment -T_f fs against the motion: fs = the
 *                                                 direction the lid moves, a state of the stroke;
 *                                                 at rest (release, a turning point, located to
 *                                                 the method's order) it sticks unless |V'| > T_fr
 *   strut     |D - E|            |dl|             F_R along the spring: with friction the moment
 *   friction                                      T_fr = T_f + F_R |l'| against the motion
 *
 * The laws are macros over numbers, so the scalar code (double) and the SIMD lanes (v4) use
 * the same operations in the same order. For the early exit every conservative law also
 * states the least potential and the range of its slope term over a piece where q and q'
 * lie in given ranges (law_linear_bounds): the bound of the reachable speeds is built from
 * them (speed_piece_ok).
 *
 * Everything the kernel knows of the elements is in this section: the design row's columns
 * (D_*), the parameters of a row (Par) and of a group of lanes (Par4), how a row is read
 * (ELEM_READ) and copied into its lane (ELEM_LANE), which element columns the coordinate
 * table holds (X_*), and the laws. The elements of the fixed table (gravity, spring,
 * dashpot, rotary damper at the lid) are summed by ELEM_SLOPE ...; those of the coordinate
 * table (the torsion spring, the rotary damper at a pivot) by ELEM_SLOPE_X ..., added where a
 * row has them (Par.x; Par4.anyx for a group). */

/* the design-row columns (D_*, NDESIGN): _layout.h, in the registry's order */
/* then, optionally, the row's own attachment points (PER-ROW ATTACHMENT POINTS, below): the
 * spring's anchor D (world) and lid point E (lid frame, from A), the dashpot's anchor F
 * (world) and lid point H (lid frame), x and y each; NaN: the table's own */
enum { D_PT = NDESIGN, NPT = 8 };
/* the coordinate table's columns: the torsion spring's psi and dpsi at its pivot, the rotary
 * damper's psi'^2 at its pivot */
/* (X_PSI, X_DPSI, X_DPR2: _layout.h) */

/* one row's element parameters (SI); F: the spring's signed preload s F0; cr / crp: the
 * rotary damper at the lid / at a pivot (the table says which: rotary_at_pivot); ow: the
 * dampers are one-way; Tf: dry friction, fs: the way the lid moves (its state: set at the
 * release and at every turning point); dm = m_lid - m0: 0 for a row at the table's mass; x:
 * the row has an element of the coordinate table; the end damper: ce (c_e), the (theta_e), e: it
 * can engage on this stroke (ce != 0, theta_e above theta_closed: ELEM_ENGAGE_START), eg: the
 * lane is engaged (its state, switched at each crossing of theta_e), cen = eg ? ce : 0 (the
 * damping it adds now); ps, pd: the row has its own spring / dashpot points */
/* a row's own pieces of l, dl, dd on a block of PKB cells (PER-ROW ATTACHMENT POINTS) */
#define PKB 8 /* cells a block of a row's own pieces holds */
typedef struct { int base, nb; double blk[PKB][4 * NC]; } PtCache;
typedef struct { double k, l0, F, c, cr, crp, kt, psi0, Tf, fs, dm, ce, the, cen;
                 double G, gb, lc, FR; /* a gas strut's law (G, b), its compressed end lc
                                        * = l0 - s (-inf for a coil spring); strut friction */
                 int x, ow, e, eg, anyg; /* anyg: a gas strut (G != 0) */
                 int ps, pd; double pt[NPT]; /* own spring / dashpot points (D_PT ...) */
                 PtCache *pc; /* their pieces (with ps or pd) */ } Par;
/* the lanes' parameters as vectors; any: a lane at another lid mass; anyx: a lane with
 * element columns (its element terms are added for every lane of the group: the others add
 * a zero, k_t = 0); anye: a lane with an end damper (cen added for every lane of the group:
 * the others add a zero; the = -inf and egm = 0 in them, so no crossing is ever seen) */
typedef struct { v4 k, l0, F, c, cr, crp, kt, psi0, Tf, fs, cen, the, G, gb, FR; v4l ow, egm;
                 double dm[VW]; int any, anyx, anyow, anyf, anye, anyg;
                 const Par *lp[VW]; int lpts[VW], anyp; /* the lanes' rows; which have
                                                          * points; any of them */ } Par4;
/* read a design row d of table T into p (not dm) */
#define ELEM_READ(p, d, T) do { \
        (p)->k = (d)[D_SPRING_K]; (p)->l0 = (d)[D_SPRING_REST_LENGTH]; (p)->c = (d)[D_DAMPER_C]; (p)->cr = (d)[D_ROTARY_DAMPER_C]; \
        (p)->crp = 0.0; \
        if ((T)->rot_pivot) { (p)->crp = (p)->cr; (p)->cr = 0.0; } \
        (p)->F = (d)[D_SPRING_KIND] * (d)[D_SPRING_PRELOAD]; (p)->G = 0.0; (p)->gb = 0.0; \
        (p)->lc = -INFINITY; \
        if ((d)[D_SPRING_KIND] == KIND_GAS) { \
            double s_ = (d)[D_STRUT_STROKE] > 0 ? (d)[D_STRUT_STROKE] : STROKE_FRACTION * (p)->l0; \
            (p)->G = -(d)[D_SPRING_PRELOAD]; (p)->gb = (1.0 - 1.0 / (d)[D_STRUT_PROGRESSION]) / s_; \
            (p)->lc = (p)->l0 - s_; (p)->F = 0.0; (p)->k = 0.0; \
        } \
        (p)->anyg = (p)->G != 0.0; \
        (p)->FR = (d)[D_STRUT_FRICTION]; \
        (p)->kt = (d)[D_TORSION_K]; (p)->psi0 = (d)[D_TORSION_FREE_ANGLE]; (p)->ow = (d)[D_DAMPER_ONE_WAY] != 0.0; \
        (p)->Tf = (d)[D_FRICTION_TORQUE]; (p)->fs = 0.0; \
        (p)->x = (p)->kt != 0.0 || (p)->crp != 0.0; \
        (p)->ce = (d)[D_END_DAMPER_C]; (p)->the = (d)[D_END_DAMPER_ANGLE]; (p)->e = 0; (p)->eg = 0; (p)->cen = 0.0; \
    } while (0)
/* the end damper's state at the release from th0 (stroke ending at thc): it can engage if
 * c_e != 0 and theta_e lies above the rim (else it never acts: the lid closes first, as in
 * the reference); engaged from the start when th0 < theta_e */
#define ELEM_ENGAGE_START(p, th0, thc) do { \
        (p)->e = (p)->ce != 0.0 && (p)->the > (thc); \
        (p)->eg = (p)->e && (th0) < (p)->the; \
        (p)->cen = (p)->eg ? (p)->ce : 0.0; \
    } while (0)
/* switch the end damper's state (at a crossing of theta_e) */
#define ELEM_ENGAGE_SWITCH(p) do { \
        (p)->eg = !(p)->eg; (p)->cen = (p)->eg ? (p)->ce : 0.0; \
    } while (0)
/* has the lane crossed theta_e (th1: the angle at the end of its step)? */
#define ELEM_CROSSED(p, th1) ((p)->e && ((th1) < (p)->the) != (p)->eg)
/* copy row p into lane q of the group G (then G->anyx |= p->x) */
#define ELEM_LANE(G, q, p) do { \
        (G)->k[q] = (p)->k; (G)->l0[q] = (p)->l0; (G)->c[q] = (p)->c; (G)->cr[q] = (p)->cr; \
        (G)->F[q] = (p)->F; (G)->G[q] = (p)->G; (G)->gb[q] = (p)->gb; (G)->FR[q] = (p)->FR; \
        (G)->kt[q] = (p)->kt; (G)->psi0[q] = (p)->psi0; (G)->crp[q] = (p)->crp; \
        (G)->ow[q] = -(long long)(p)->ow; (G)->Tf[q] = (p)->Tf; (G)->fs[q] = (p)->fs; \
        ELEM_LANE_ENGAGE(G, q, p); \
    } while (0)
/* the end damper's state of lane q (also after each of its crossings) */
#define ELEM_LANE_ENGAGE(G, q, p) do { \
        (G)->cen[q] = (p)->cen; (G)->the[q] = (p)->e ? (p)->the : -INFINITY; \
        (G)->egm[q] = -(long long)(p)->eg; \
    } while (0)
/* the kernel's number of a gas strut (softclose.model.elements.springs.GAS) and a strut's
 * stroke as a fraction of its extended length when none is given (STROKE_FRACTION) */
#define KIND_GAS (-2.0)
#define STROKE_FRACTION 0.4
#define LAW_LINEAR_T(k, q0, q) ((k) * ((q) - (q0)))                  /* T = dV/dq */
#define LAW_LINEAR_V(k, q0, q) (0.5 * (k) * ((q) - (q0)) * ((q) - (q0)))
/* d/dtheta of T q' (for the implicit methods' Jacobian): k (q'^2 + (q - q0) q'') */
#define LAW_LINEAR_DSLOPE(k, q0, q, dq_th, dq, ddq) ((k) * ((dq_th) * (dq) + ((q) - (q0)) * (ddq)))
/* the same with a preload F (a constant tension): T = F + k (q - q0), V = k (q - q0)^2 / 2 + F q */
#define LAW_PRELOADED_T(k, q0, F, q) ((F) + LAW_LINEAR_T(k, q0, q))
#define LAW_PRELOADED_V(k, q0, F, q) (LAW_LINEAR_V(k, q0, q) + (F) * (q))
#define LAW_PRELOADED_DSLOPE(k, q0, F, q, dq_th, dq, ddq) \
    (LAW_LINEAR_DSLOPE(k, q0, q, dq_th, dq, ddq) + (F) * (ddq))

/* a gas strut at u = q - l0 (its extended length): T = G / (1 + b u) with G = -F1 (it
 * pushes), b = (1 - 1/K)/s; dT/dq; V = G u psi(b u), psi(z) = ln(1 + z)/z (psi(0) = 1: a
 * constant force with K = 1). G = b = 0 for every other spring: T = 0/1 = 0, V = 0 */
#define LAW_GAS_T(G, b, u) ((G) / (1.0 + (b) * (u)))
#define LAW_GAS_DT(G, b, u) (-(G) * (b) / ((1.0 + (b) * (u)) * (1.0 + (b) * (u))))
/* psi(z) = ln(1 + z)/z, the same operations on numbers and on lanes (so a lane's energy is
 * the same in the vector path and the scalar one): with w = 1 + z rounded, psi = ln(w)/(w - 1)
 * (exact for the rounded w, and psi varies slowly: a few ulp, as log1p(z)/z), ln w = e ln 2
 * + ln m with w = m 2^e, m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh(s) = 2 s (1 + s^2/3 +
 * s^4/5 + ...), s = (m - 1)/(m + 1), |s| <= 0.172: 13 terms reach 1e-17. A log per lane and
 * node was most of a gas strut's time per step; this runs four lanes at once. |z| < 1e-8:
 * 1 - z/2; w <= 0 (beyond a strut's range): NaN, as log1p. */
#define PSI_TERMS 13
static const double PSI_C[PSI_TERMS] = {
    1.0, 1.0 / 3, 1.0 / 5, 1.0 / 7, 1.0 / 9, 1.0 / 11, 1.0 / 13, 1.0 / 15, 1.0 / 17,
    1.0 / 19, 1.0 / 21, 1.0 / 23, 1.0 / 25};
#define LN2_HI 6.93147180369123816490e-01 /* ln 2 split (fdlibm's): e ln2_hi is exact */
#define LN2_LO 1.90821492927058770002e-10
static inline double gas_psi(double z)
{
    if (fabs(z) < 1e-8) return 1.0 - 0.5 * z;
    double w = 1.0 + z;
    if (!(w > 0.0) || !(w < INFINITY)) return NAN;
    long long bits;
    memcpy(&bits, &w, sizeof bits);
    long long e = ((bits >> 52) & 0x7ff) - 1023;
    long long mb = (bits & 0x000fffffffffffffLL) | 0x3ff0000000000000LL;
    double m;
    memcpy(&m, &mb, sizeof m);
    if (m > 1.4142135623730951) { m = 0.5 * m; e += 1; }
    double s = (m - 1.0) / (m + 1.0), s2 = s * s, poly = PSI_C[PSI_TERMS - 1];
    for (int i = PSI_TERMS - 2; i >= 0; i--) poly = poly * s2 + PSI_C[i];
    double de = (double)e;
    double lnw = de * LN2_HI + (de * LN2_LO + 2.0 * s * poly);
    return lnw / (w - 1.0);
}
static inline v4 gas_psi4(v4 z)
{
    const v4 one = {1.0, 1.0, 1.0, 1.0}, half = {0.5, 0.5, 0.5, 0.5};
    v4 w = one + z;
    v4l bits = (v4l)w;
    v4l e = ((bits >> 52) & 0x7ff) - 1023;
    v4 m = (v4)((bits & 0x000fffffffffffffLL) | 0x3ff0000000000000LL);
    v4l big = m > 1.4142135623730951;
    m = sel4(big, half * m, m);
    e -= big;                                     /* (true is -1 in a lane mask) */
    v4 s = (m - one) / (m + one), s2 = s * s, poly = s2 * 0.0 + PSI_C[PSI_TERMS - 1];
    for (int i = PSI_TERMS - 2; i >= 0; i--) poly = poly * s2 + PSI_C[i];
    v4 de = {(double)e[0], (double)e[1], (double)e[2], (double)e[3]};
    v4 lnw = de * LN2_HI + (de * LN2_LO + 2.0 * s * poly);
    v4 r = lnw / (w - one);
    v4l small = abs4(z) < 1e-8, bad = ~small & (~(w > 0.0) | ~(w < INFINITY));
    return sel4(small, one - half * z, sel4(bad, one * NAN, r));
}
static inline double law_gas_v(double G, double b, double u)
{
    if (G == 0.0) return 0.0;
    return G * u * gas_psi(b * u);
}
static inline v4 law_gas_v4(v4 G, v4 b, v4 u)
{
    v4 r = G * u * gas_psi4(b * u);
    return sel4(G == 0.0, (v4){0.0, 0.0, 0.0, 0.0}, r);   /* not a strut: 0, as law_gas_v */
}
/* (numbers or lanes alike) */
#define LAW_GAS_V(G, b, u) _Generic((G), v4: law_gas_v4, default: law_gas_v)(G, b, u)
#define ELEM_ABS(x) _Generic((x), v4: abs4, default: fabs)(x)
/* the spring's tension T(l): its coil law and its gas law (one of them 0) */
#define ELEM_SPRING_T(P, l) (LAW_PRELOADED_T((P)->k, (P)->l0, (P)->F, l) \
    + ((P)->anyg ? LAW_GAS_T((P)->G, (P)->gb, (l) - (P)->l0) : 0.0 * (l)))
/* the slope dV/dtheta of gravity and the spring, from the coefficient values c[] (numbers
 * or lanes); a row with element columns (has x) adds the torsion spring's term from x[] */
#define ELEM_SLOPE(P, cv) ((cv)[C_DVG] + ELEM_SPRING_T(P, (cv)[C_L]) * (cv)[C_DL])
#define ELEM_SLOPE_X(P, x) (LAW_LINEAR_T((P)->kt, (P)->psi0, (x)[X_PSI]) * (x)[X_DPSI])
/* the potential V of gravity and the spring (then + ELEM_POTENTIAL_X); the energy is the
 * kinetic energy KE plus the same potentials, summed in this order */
#define ELEM_SPRING_V(P, l) (LAW_PRELOADED_V((P)->k, (P)->l0, (P)->F, l) \
    + ((P)->anyg ? LAW_GAS_V((P)->G, (P)->gb, (l) - (P)->l0) : 0.0 * (l)))
#define ELEM_POTENTIAL(P, cv) ((cv)[C_VG] + ELEM_SPRING_V(P, (cv)[C_L]))
#define ELEM_ENERGY(P, cv, KE) ((KE) + (cv)[C_VG] + ELEM_SPRING_V(P, (cv)[C_L]))
#define ELEM_POTENTIAL_X(P, x) LAW_LINEAR_V((P)->kt, (P)->psi0, (x)[X_PSI])
/* the damping on theta': the dashpot and the rotary damper at the lid (then + the rotary
 * damper at a pivot, from x[]); a one-way row's damping is 0 while th' > 0 */
#define ELEM_DAMPING(P, cv) ((P)->c * (cv)[C_DD] + (P)->cr)
#define ELEM_DAMPING_X(P, x) ((P)->crp * (x)[X_DPR2])
/* the end damper's damping now (0 unless the lane is engaged): added after the others, where
 * a row has one (Par.e; Par4.anye for a group) */
#define ELEM_DAMPING_E(P) ((P)->cen)
#define ELEM_ONE_WAY(p, thd, damp) ((p)->ow && (thd) > 0 ? 0.0 : (damp))
/* dry friction's moment T_fr = T_f + F_R |l'| (the lumped friction and the strut's) and
 * its moment against the motion (fs: the lane's direction, set at its rests) */
#define ELEM_FRICTION_MOMENT(p, cv) ((p)->Tf + (p)->FR * ELEM_ABS((cv)[C_DL]))
#define ELEM_FRICTION(p, cv) (ELEM_FRICTION_MOMENT(p, cv) * (p)->fs)
/* d/dtheta of the slope and of the damping (values c, x; their derivatives dc, dx) */
#define ELEM_DSLOPE(P, cv, dcv) \
    ((dcv)[C_DVG] + LAW_PRELOADED_DSLOPE((P)->k, (P)->l0, (P)->F, (cv)[C_L], (dcv)[C_L], \
                                         (cv)[C_DL], (dcv)[C_DL]) \
     + ((P)->anyg ? LAW_GAS_DT((P)->G, (P)->gb, (cv)[C_L] - (P)->l0) * (dcv)[C_L] * (cv)[C_DL] \
        + LAW_GAS_T((P)->G, (P)->gb, (cv)[C_L] - (P)->l0) * (dcv)[C_DL] : 0.0 * (cv)[C_L]))
#define ELEM_DSLOPE_X(P, x, dx) \
    LAW_LINEAR_DSLOPE((P)->kt, (P)->psi0, (x)[X_PSI], (dx)[X_PSI], (x)[X_DPSI], (dx)[X_DPSI])
#define ELEM_DDAMPING(P, dcv) ((P)->c * (dcv)[C_DD])
#define ELEM_DDAMPING_X(P, dx) ((P)->crp * (dx)[X_DPR2])
/* does the row dissipate (the early exit's condition)? The end damper counts once the lane
 * is engaged (cen > 0: checked at the release and at each engagement): a lid that never
 * reaches theta_e is undamped, and runs to t_max as one without the end damper */
#define ELEM_DISSIPATES(P) ((P)->c > 0 || (P)->cr > 0 || (P)->crp > 0 || (P)->cen > 0)
/* a friction row stops at its first stick, exactly: the energy rule is not used for it */
#define ELEM_STICKS(P) ((P)->Tf > 0 || (P)->FR > 0)
#define ELEM_DAMPERS_VALID(P) ((P)->c >= 0 && (P)->cr >= 0 && (P)->crp >= 0 && (P)->ce >= 0)
/* the size of the springs' potential terms (the energy's rounding scale) */
#define ELEM_SIZE(P, cv) (fabs((cv)[C_VG]) + 0.5 * fabs((P)->k) * ((cv)[C_L] - (P)->l0) \
                          * ((cv)[C_L] - (P)->l0) + fabs((P)->F * (cv)[C_L]) \
                          + fabs((P)->G * ((cv)[C_L] - (P)->l0)))
#define ELEM_SIZE_X(P, x) fabs(ELEM_POTENTIAL_X(P, x))

/* a linear law on q in [qlo, qhi] with q' in [dlo, dhi]: its least potential and the range
 * [slo, shi] of its slope term T q' */
static inline void law_linear_bounds(double k, double q0, double qlo, double qhi, double dlo,
                                     double dhi, double *Vmin, double *slo, double *shi)
{
    double d = q0 < qlo ? qlo - q0 : (q0 > qhi ? q0 - qhi : 0.0);
    *Vmin = 0.5 * k * d * d;
    double e1 = qlo - q0, e2 = qhi - q0;
    double x1 = e1 * dlo, x2 = e1 * dhi, x3 = e2 * dlo, x4 = e2 * dhi;
    double plo = MIN2(MIN2(x1, x2), MIN2(x3, x4)), phi = MAX2(MAX2(x1, x2), MAX2(x3, x4));
    *slo = k * plo; *shi = k * phi;
}

/* a gas strut's law (G, b; extended length q0) on q in [qlo, qhi] with q' in [dlo, dhi]:
 * its least potential and the range of T q'. T = G / (1 + b (q - q0)) is monotone in q and
 * V' = T keeps G's sign, so both come from the ends; beyond the law's pole (1 + b u <= 0,
 * far past the strut's stroke: an invalid design) nothing is bounded */
static inline void law_gas_bounds(double G, double b, double q0, double qlo, double qhi,
                                  double dlo, double dhi, double *Vmin, double *slo,
                                  double *shi)
{
    double ulo = qlo - q0, uhi = qhi - q0;
    if (!(1.0 + b * ulo > 0.0 && 1.0 + b * uhi > 0.0)) {
        *Vmin = -INFINITY; *slo = -INFINITY; *shi = INFINITY; return;
    }
    double Va = law_gas_v(G, b, ulo), Vb = law_gas_v(G, b, uhi);
    *Vmin = MIN2(Va, Vb);
    double t1 = LAW_GAS_T(G, b, ulo), t2 = LAW_GAS_T(G, b, uhi);
    double x1 = t1 * dlo, x2 = t1 * dhi, x3 = t2 * dlo, x4 = t2 * dhi;
    *slo = MIN2(MIN2(x1, x2), MIN2(x3, x4)); *shi = MAX2(MAX2(x1, x2), MAX2(x3, x4));
}

/* the same with a preload F (V = k (q - q0)^2 / 2 + F q): the least potential from the
 * vertex q0 - F/k clamped into [qlo, qhi] (or the end F picks, k = 0), and the slope range
 * of k (q - q0) q' plus that of F q' */
static inline void law_preloaded_bounds(double k, double q0, double F, double qlo, double qhi,
                                        double dlo, double dhi, double *Vmin, double *slo,
                                        double *shi)
{
    law_linear_bounds(k, q0, qlo, qhi, dlo, dhi, Vmin, slo, shi);
    if (F == 0.0) return;
    double qv = k > 0 ? q0 - F / k : (F > 0 ? qlo : qhi);
    qv = qv < qlo ? qlo : (qv > qhi ? qhi : qv);
    *Vmin = LAW_PRELOADED_V(k, q0, F, qv);
    double f1 = F * dlo, f2 = F * dhi;
    *slo += MIN2(f1, f2); *shi += MAX2(f1, f2);
}

static void cubic_range(const double *q, double s0, double s1, double *lo, double *hi);

/* the coordinate table's conservative elements over cell i, s in [s0, s1]: their least potential
 * and slope range (from the ranges of their columns' cubic pieces), added to V1 and [slo, shi] */
static void elem_bounds_x(const double *xcc, const Par *p, int i, double s0, double s1,
                          double *V1, double *slo, double *shi)
{
    double xq[4], qlo, qhi, dlo, dhi, V, lo, hi;
    for (int e = 0; e < 4; e++) xq[e] = xcc[((size_t)i * 4 + e) * NX + X_PSI];
    cubic_range(xq, s0, s1, &qlo, &qhi);
    for (int e = 0; e < 4; e++) xq[e] = xcc[((size_t)i * 4 + e) * NX + X_DPSI];
    cubic_range(xq, s0, s1, &dlo, &dhi);
    law_linear_bounds(p->kt, p->psi0, qlo, qhi, dlo, dhi, &V, &lo, &hi);
    *V1 += V; *slo += lo; *shi += hi;
}
/* ===== (end of the machine elements) ======================================================== */

/* index of the table cell holding th and the local variable s in [0, 1]; -1 outside */
static inline int cell_index(const Table *T, double th, double *s)
{
    double x = (th - T->lo) * T->inv_h;
    if (!(x >= 0.0 && x <= (double)T->ncell)) return -1;
    int i = (int)x;
    if (i >= T->ncell) i = T->ncell - 1;
    *s = x - i;
    return i;
}

/* ---- CUBIC PIECES: the one Horner evaluation of the kernel ---------------------------------
 * Every tabulated function is a cubic q0 + q1 s + q2 s^2 + q3 s^3 in the local variable s of
 * its cell (s in [0, 1]); its four coefficients lie `stride` doubles apart (the tables are
 * power-major: stride NC, NX or NPOSE from the column's first coefficient; a lone cubic: 1).
 * cubic() is its value, dcubic() its theta-derivative (ih = 1/h), cubic4() four neighbouring
 * columns at once (a v4, for the lanes). Every evaluation of a piece is one of these, in this
 * order of operations, so the scalar and the SIMD paths agree bit for bit. */
ALWAYS double cubic(const double *q, int stride, double s)
{
    return q[0] + s * (q[stride] + s * (q[2 * stride] + s * q[3 * stride]));
}

ALWAYS double dcubic(const double *q, int stride, double s, double ih)
{
    return (q[stride] + s * (2.0 * q[2 * stride] + s * 3.0 * q[3 * stride])) * ih;
}

ALWAYS v4 cubic4(const double *q, int stride, double s)
{
    return ld4(q) + s * (ld4(q + stride) + s * (ld4(q + 2 * stride) + s * ld4(q + 3 * stride)));
}

/* the element columns x[NX] (and their theta-derivatives dx, may be NULL) in cell i at s */
static inline void xtab_eval(const Table *T, int i, double s, double *x, double *dx)
{
    const double *q = T->xcc + (size_t)i * 4 * NX;
    for (int j = 0; j < NX; j++) {
        x[j] = cubic(q + j, NX, s);
        if (dx) dx[j] = dcubic(q + j, NX, s, T->inv_h);
    }
}

/* ===== PER-ROW ATTACHMENT POINTS ===========================================================
 * A row may carry its own spring points (anchor D, world; lid point E, lid frame from pin A)
 * and dashpot points (anchor F, world; lid point H, lid frame) after m_lid (D_PT, NPT; NaN,
 * or no such columns: the table's own l, dl, dd, read as always -- bit-identical). Every lid
 * point is P(th) = A(th) + R(th) p, A the crank pin, so the pose table (pcc: cubic Hermite
 * pieces of A, A' = dA/dth, cos th, sin th on the table's cells, built like the other
 * columns from the CasADi model with exact derivatives) holds at each node the exact A, A',
 * A'', cos, sin; from them, for a lid point p and a ground point G,
 *     r = A + R p - G,   r' = A' + z x (R p),   r'' = A'' - R p,
 *     l = |r|,   l' = r.r' / l,   l'' = (|r'|^2 + r.r'' - l'^2) / l,
 *     dashpot: q'^2 = (r.r')^2 / |r|^2 and its slope.
 * A row's own cubic Hermite pieces of l, dl (spring) and dd (dashpot) on a cell are built
 * from these node values and slopes exactly as the table builds its own (table.py _pieces),
 * so a row's pieces are those of a table built at its points, to the rounding of the node
 * values. They are built when a stroke first enters a cell, for a block of PKB = 8 cells
 * ahead of it in the way it goes (pt_piece, pt_build; the nodes four a vector, pt_nodes_avx2,
 * the same numbers as node by node, pt_nodes_any): a stroke visits a few hundred of the
 * table's cells, and a lid creeping towards an equilibrium stays in one for many steps. They
 * are laid out as the table's cells (power-major, with the table's tau beside them), so the
 * kernel reads them wherever it reads l, dl, dd: the scalar code from the row's piece (cubic),
 * the SIMD lanes from it as their second vector (coef4_pts, in rhs4_pts / node4_pts: a group
 * with points runs its own copy, the others keep theirs) -- the same operations as for the
 * table's columns, so the scalar and SIMD paths agree bit for bit and a row's numbers do
 * not depend on which cells were kept. The
 * early exit stays exact: the ranges of l and l' over a piece are those of the row's cubic
 * pieces (as for the table's), and the spring-length extremes over [th_min, th_max] are
 * found on the row's pieces in the cells where a mean-value bound of l' (from bounds of
 * |A'|, |A''| over the table) does not rule an extremum out (l_extremes_pts). A length that
 * vanishes (a lid point through its anchor) makes l' non-finite: the stroke stops
 * (S_NONFINITE or S_RANGE), never a number from it. */

/* r and r' of a lid point (px, py) and a ground point (gx, gy) from the pose values a[] */
#define PT_R(a, px, py, gx, gy, rx, ry, ux, uy) do { \
        double qx_ = (a)[P_COS] * (px) - (a)[P_SIN] * (py); \
        double qy_ = (a)[P_SIN] * (px) + (a)[P_COS] * (py); \
        (rx) = (a)[P_AX] + qx_ - (gx); (ry) = (a)[P_AY] + qy_ - (gy); \
        (ux) = (a)[P_DAX] - qy_; (uy) = (a)[P_DAY] + qx_; \
    } while (0)

/* set the row's own points pt[NPT] (NaN: the table's) into p, its cache emptied */
static inline void pts_set(Par *p, const double *pt)
{
    for (int j = 0; j < NPT; j++) p->pt[j] = pt[j];
    p->ps = isfinite(pt[0]) && isfinite(pt[1]) && isfinite(pt[2]) && isfinite(pt[3]);
    p->pd = isfinite(pt[4]) && isfinite(pt[5]) && isfinite(pt[6]) && isfinite(pt[7]);
    if (p->pc) p->pc->base = p->pc->nb = 0;
}

/* read the row's own points (columns D_PT.. of a row of ncol columns) into p */
static inline void pts_read(Par *p, const double *d, int ncol)
{
    p->ps = p->pd = 0;
    if (ncol >= D_PT + NPT) pts_set(p, d + D_PT);
}

/* one length of a row's points from the pose values a (and their theta-derivatives da, or
 * NULL): l and l' (spring: dash = 0), or q'^2 (dashpot: dash = 1) into v, their
 * theta-derivatives into dv (with da) */
static inline void pt_length(const double *a, const double *da, const double *g, int dash,
                             double *v, double *dv)
{
    double rx, ry, ux, uy;
    PT_R(a, g[2], g[3], g[0], g[1], rx, ry, ux, uy);
    double l2 = rx * rx + ry * ry, w = rx * ux + ry * uy;
    double l = 0.0, dl = 0.0;
    if (dash) v[C_DD] = w * w / l2;
    else { l = sqrt(l2); dl = w / l; v[C_L] = l; v[C_DL] = dl; }
    if (!da) return;
    double qx = a[P_COS] * g[2] - a[P_SIN] * g[3], qy = a[P_SIN] * g[2] + a[P_COS] * g[3];
    double wd = ux * ux + uy * uy + rx * (da[P_DAX] - qx) + ry * (da[P_DAY] - qy);
    if (dash) dv[C_DD] = 2.0 * w * (wd * l2 - w * w) / (l2 * l2);
    else { dv[C_L] = dl; dv[C_DL] = (wd - dl * dl) / l; }
}

/* the pose at node j = 0..ncell (values a, theta-derivatives da): the ends of the pieces,
 * which hold the exact node values and slopes (the right end from the next cell's start) */
static inline void pose_node(const Table *T, int j, double *a, double *da)
{
    if (j < T->ncell) {
        const double *q = T->pcc + (size_t)j * 4 * NPOSE;
        for (int k = 0; k < P_USED; k++) { a[k] = q[k]; da[k] = q[NPOSE + k] * T->inv_h; }
    } else {
        const double *q = T->pcc + (size_t)(T->ncell - 1) * 4 * NPOSE;
        for (int k = 0; k < P_USED; k++) {
            a[k] = cubic(q + k, NPOSE, 1.0);
            da[k] = dcubic(q + k, NPOSE, 1.0, T->inv_h);
        }
    }
}

/* the row's l, dl, dd (f[m][k], m = 0, 1, 2) and their slopes (d[m][k]) at the nodes
 * j0 + k, k < nn <= PKB + 1: pt_length node by node, or (pt_nodes_avx2) four nodes a vector
 * with the same operations in the same order -- the same numbers bit for bit */
#define PNN 12 /* PKB + 1 nodes, rounded up to whole vectors */
static void pt_nodes_any(const Table *T, const Par *p, int j0, int nn, double f[3][PNN],
                         double d[3][PNN])
{
    for (int k = 0; k < nn; k++) {
        double a[P_USED], da[P_USED], v[NC], dv[NC];
        pose_node(T, j0 + k, a, da);
        v[C_L] = v[C_DL] = v[C_DD] = dv[C_L] = dv[C_DL] = dv[C_DD] = 0.0;
        if (p->ps) pt_length(a, da, p->pt, 0, v, dv);
        if (p->pd) pt_length(a, da, p->pt + 4, 1, v, dv);
        for (int m = 0; m < 3; m++) { f[m][k] = v[C_L + m]; d[m][k] = dv[C_L + m]; }
    }
}

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define PT_AVX2 1
__attribute__((target("avx2"), noinline))
static void pt_nodes_avx2(const Table *T, const Par *p, int j0, int nn, double f[3][PNN],
                          double d[3][PNN])
{
    double a[P_USED][PNN], da[P_USED][PNN];
    for (int k = 0; k < PNN; k++) {
        double x[P_USED], dx[P_USED];
        pose_node(T, k < nn ? j0 + k : j0, x, dx);
        for (int j = 0; j < P_USED; j++) { a[j][k] = x[j]; da[j][k] = dx[j]; }
    }
    const v4 two = {2.0, 2.0, 2.0, 2.0}, zero = {0.0, 0.0, 0.0, 0.0};
    for (int k = 0; k < PNN; k += VW) {
        v4 c = ld4(a[P_COS] + k), sn = ld4(a[P_SIN] + k), ax = ld4(a[P_AX] + k),
           ay = ld4(a[P_AY] + k), dx = ld4(a[P_DAX] + k), dy = ld4(a[P_DAY] + k),
           ddx = ld4(da[P_DAX] + k), ddy = ld4(da[P_DAY] + k);
        v4 fl = zero, fdl = zero, fdd = zero, dl_ = zero, ddl = zero, ddd = zero;
        for (int dash = 0; dash < 2; dash++) { /* pt_length's operations, as vectors */
            if (dash ? !p->pd : !p->ps) continue;
            const double *g = p->pt + 4 * dash;
            v4 qx = c * g[2] - sn * g[3], qy = sn * g[2] + c * g[3];
            v4 rx = ax + qx - g[0], ry = ay + qy - g[1], ux = dx - qy, uy = dy + qx;
            v4 l2 = rx * rx + ry * ry, w = rx * ux + ry * uy;
            v4 qx2 = c * g[2] - sn * g[3], qy2 = sn * g[2] + c * g[3];
            v4 wd = ux * ux + uy * uy + rx * (ddx - qx2) + ry * (ddy - qy2);
            if (dash) {
                fdd = w * w / l2;
                ddd = two * w * (wd * l2 - w * w) / (l2 * l2);
            } else {
                v4 l = __builtin_ia32_sqrtpd256(l2), dl = w / l;
                fl = l; fdl = dl; dl_ = dl;
                ddl = (wd - dl * dl) / l;
            }
        }
        memcpy(f[0] + k, &fl, sizeof fl); memcpy(f[1] + k, &fdl, sizeof fl);
        memcpy(f[2] + k, &fdd, sizeof fl); memcpy(d[0] + k, &dl_, sizeof fl);
        memcpy(d[1] + k, &ddl, sizeof fl); memcpy(d[2] + k, &ddd, sizeof fl);
    }
}
#endif

static int use_vec;

/* build the row's pieces on a block of PKB cells holding cell i (ahead of it in the way the
 * stroke goes: below it when it came from above) -- noinline: once a block */
__attribute__((noinline)) static const double *pt_build(const Table *T, const Par *p, int i)
{
    PtCache *c = p->pc;
    int base = c->nb && i < c->base ? i - PKB + 1 : i;
    if (base > T->ncell - PKB) base = T->ncell - PKB;
    if (base < 0) base = 0;
    int nb = T->ncell - base < PKB ? T->ncell - base : PKB;
    c->base = base; c->nb = nb;
    double f[3][PNN], d[3][PNN];
#ifdef PT_AVX2
    if (use_vec > 0) pt_nodes_avx2(T, p, base, nb + 1, f, d);
    else
#endif
        pt_nodes_any(T, p, base, nb + 1, f, d);
    for (int k = 0; k < nb; k++) {
        double *b = c->blk[k];
        const double *t = T->cc + (size_t)(base + k) * 4 * NC;
        for (int e = 0; e < 4; e++)
            for (int j = C_L; j <= C_TAU; j++) b[e * NC + j] = t[e * NC + j]; /* the table's */
        for (int j = C_L; j <= C_DD; j++) {
            if (j == C_DD ? !p->pd : !p->ps) continue;
            int m = j - C_L;
            double f0 = f[m][k], f1 = f[m][k + 1], d0 = d[m][k] * T->h, d1 = d[m][k + 1] * T->h;
            b[j] = f0; b[NC + j] = d0;
            b[2 * NC + j] = 3 * (f1 - f0) - 2 * d0 - d1;
            b[3 * NC + j] = 2 * (f0 - f1) + d0 + d1;
        }
    }
    return c->blk[i - base];
}

/* the row's pieces on cell i: a block laid out as the table's cell (power-major, NC a
 * power), whose columns l, dl, dd, tau are the row's (its own where it has points) */
static inline const double *pt_piece(const Table *T, const Par *p, int i)
{
    const PtCache *c = p->pc;
    if ((unsigned)(i - c->base) < (unsigned)c->nb) return c->blk[i - c->base];
    return pt_build(T, p, i);
}

/* the row's own columns of the values v (and their theta-derivatives dv, or NULL) in cell i
 * at s, from its pieces */
static inline void pts_eval(const Table *T, const Par *p, int i, double s, double *v, double *dv)
{
    const double *q = pt_piece(T, p, i);
    for (int j = C_L; j <= C_DD; j++) {
        if (j == C_DD ? !p->pd : !p->ps) continue;
        v[j] = cubic(q + j, NC, s);
        if (dv) dv[j] = dcubic(q + j, NC, s, T->inv_h);
    }
}

/* bounds of |A'| and |A''| over the table (T->pA1, T->pA2), from the ranges of the pose
 * pieces of A' and of their slopes, widened by 1 % (the mean-value test of l_extremes_pts) */
static void pts_bounds(Table *T)
{
    double m2x = 0.0, m2y = 0.0, m1x = 0.0, m1y = 0.0;
    for (int i = 0; i < T->ncell; i++) {
        for (int j = P_DAX; j <= P_DAY; j++) {
            double q[4], dq[4], lo, hi;
            for (int e = 0; e < 4; e++) q[e] = T->pcc[((size_t)i * 4 + e) * NPOSE + j];
            cubic_range(q, 0.0, 1.0, &lo, &hi);
            double mag = MAX2(fabs(lo), fabs(hi));
            if (j == P_DAX) m1x = MAX2(m1x, mag); else m1y = MAX2(m1y, mag);
            dq[0] = q[1]; dq[1] = 2.0 * q[2]; dq[2] = 3.0 * q[3]; dq[3] = 0.0;
            cubic_range(dq, 0.0, 1.0, &lo, &hi);
            mag = MAX2(fabs(lo), fabs(hi)) * T->inv_h;
            if (j == P_DAX) m2x = MAX2(m2x, mag); else m2y = MAX2(m2y, mag);
        }
    }
    T->pA1 = 1.01 * hypot(m1x, m1y);
    T->pA2 = 1.01 * hypot(m2x, m2y);
}

static void cubic_extremes(const double *q, int i, const Table *T, double a, double b,
                           double *lmin, double *lmax);

/* l_extremes for a row with its own spring points, on the cells [j0, j1): a run of cells
 * whose middle has |l'| above the largest |l''| (<= |r'|^2 / |r| + |r''|, with
 * |r'| <= |A'| + |e|, |r''| <= |A''| + |e|, |r| >= l(mid) - |r'| half width) times its half
 * width has l monotone; the others are halved down to cells, whose pieces are searched */
static void pts_scan(const Table *T, const Par *p, int j0, int j1, double a, double b,
                     double *lmin, double *lmax, int depth)
{
    if (j1 <= j0) return;
    if (j1 - j0 > 1 && depth < 40) {
        double x0 = T->lo + j0 * T->h, x1 = T->lo + j1 * T->h;
        double xm = 0.5 * (x0 + x1), hw = 0.5 * (x1 - x0), s, v[NC] = {0};
        int i = cell_index(T, xm, &s);
        if (i >= 0) { /* (l, l' from the pose interpolated at xm: a bound, no pieces built) */
            const double *q = T->pcc + (size_t)i * 4 * NPOSE;
            double a[P_USED];
            for (int j = 0; j < P_USED; j++) a[j] = cubic(q + j, NPOSE, s);
            pt_length(a, NULL, p->pt, 0, v, NULL);
            double e = hypot(p->pt[2], p->pt[3]), R1 = T->pA1 + e, R2 = T->pA2 + e;
            double lower = v[C_L] - R1 * hw;
            if (lower > 0 && isfinite(v[C_DL])) {
                double L2 = R1 * R1 / lower + R2;
                if (fabs(v[C_DL]) > L2 * hw * (1.0 + 1e-6) + 1e-9 * v[C_L]) return;
            }
        }
        int jm = (j0 + j1) / 2;
        pts_scan(T, p, j0, jm, a, b, lmin, lmax, depth + 1);
        pts_scan(T, p, jm, j1, a, b, lmin, lmax, depth + 1);
        return;
    }
    for (int i = j0; i < j1; i++) {
        const double *r = pt_piece(T, p, i);
        double q[4] = {r[C_L], r[NC + C_L], r[2 * NC + C_L], r[3 * NC + C_L]};
        cubic_extremes(q, i, T, a, b, lmin, lmax);
    }
}

static void l_extremes_pts(const Table *T, const Par *p, double a, double b, double *lmin,
                           double *lmax)
{
    double ends[2] = {a, b}, s, v[NC] = {0};
    *lmin = INFINITY; *lmax = -INFINITY;
    for (int e = 0; e < 2; e++) {
        int i = cell_index(T, ends[e], &s);
        if (i < 0) continue;
        pts_eval(T, p, i, s, v, NULL);
        if (v[C_L] < *lmin) *lmin = v[C_L];
        if (v[C_L] > *lmax) *lmax = v[C_L];
    }
    int i0 = (int)floor((a - T->lo) / T->h), i1 = (int)floor((b - T->lo) / T->h);
    if (i0 < 0) i0 = 0;
    if (i1 > T->ncell - 1) i1 = T->ncell - 1;
    pts_scan(T, p, i0, i1 + 1, a, b, lmin, lmax, 0);
}
/* ===== (end of the per-row attachment points) ================================================ */

/* coefficient values v[NC] and theta-derivatives dv[NC] (dv may be NULL) of the row p
 * (p may be NULL: the table's own mass), and -- when x is not NULL and the row has them --
 * the element columns x[NX] and their derivatives dx */
static inline int tab_eval_x(const Table *T, const Par *p, double th, double *v, double *dv,
                             double *x, double *dx)
{
    double s;
    int i = cell_index(T, th, &s);
    if (i < 0) return 1;
    const double *q = T->cc + (size_t)i * 4 * NC;
    for (int j = 0; j < NC; j++) {
        v[j] = cubic(q + j, NC, s);
        if (dv) dv[j] = dcubic(q + j, NC, s, T->inv_h);
    }
    if (x && p && p->x) xtab_eval(T, i, s, x, dx);
    if (p && (p->ps | p->pd)) pts_eval(T, p, i, s, v, dv);
    if (p && p->dm != 0.0) {
        const double *r = T->dcc + (size_t)i * 4 * NC;
        for (int j = 0; j < NMASS; j++) {
            v[j] += p->dm * cubic(r + j, NC, s);
            if (dv) dv[j] += p->dm * dcubic(r + j, NC, s, T->inv_h);
        }
    }
    return 0;
}

static inline int tab_eval(const Table *T, const Par *p, double th, double *v, double *dv)
{
    return tab_eval_x(T, p, th, v, dv, NULL, NULL);
}

/* theta'' and, if J != NULL, J = (d th''/d th, d th''/d th') */
static inline int rhs(const Table *T, const Par *p, double th, double thd, double *thdd, double *J)
{
    double v[NC], dv[NC], x[NX], dx[NX];
    if (tab_eval_x(T, p, th, v, J ? dv : NULL, x, J ? dx : NULL)) return 1;
    double damp = ELEM_DAMPING(p, v), slope = ELEM_SLOPE(p, v);
    if (p->x) { slope += ELEM_SLOPE_X(p, x); damp += ELEM_DAMPING_X(p, x); }
    if (p->e) damp += ELEM_DAMPING_E(p); /* (constant in theta: no term in ddamp) */
    damp = ELEM_ONE_WAY(p, thd, damp);
    double N = -slope - 0.5 * v[C_DM] * thd * thd - damp * thd;
    if (ELEM_STICKS(p)) N -= ELEM_FRICTION(p, v);
    *thdd = N / v[C_M];
    if (J) {
        double dslope = ELEM_DSLOPE(p, v, dv), ddamp = ELEM_DDAMPING(p, dv);
        if (p->x) { dslope += ELEM_DSLOPE_X(p, x, dx); ddamp += ELEM_DDAMPING_X(p, dx); }
        ddamp = ELEM_ONE_WAY(p, thd, ddamp);
        double Nth = -dslope - 0.5 * dv[C_DM] * thd * thd - ddamp * thd;
        J[0] = (Nth - *thdd * dv[C_M]) / v[C_M];
        J[1] = (-v[C_DM] * thd - damp) / v[C_M];
    }
    return 0;
}

/* potential V = Vg + k (l - l0)^2 / 2 and its tabulated slope dVg + k (l - l0) dl in cell
 * i at s (four cubics) */
static inline void potential_at(const Table *T, const Par *p, int i, double s, double *V,
                                double *dV)
{
    const double *q = T->cc + (size_t)i * 4 * NC;
    double c[NC], x[NX] = {0};
    c[C_VG] = cubic(q + C_VG, NC, s); c[C_L] = cubic(q + C_L, NC, s);
    c[C_DVG] = dV ? cubic(q + C_DVG, NC, s) : 0.0; c[C_DL] = dV ? cubic(q + C_DL, NC, s) : 0.0;
    if (p->ps) pts_eval(T, p, i, s, c, NULL); /* (its l and l'; its dd is not read) */
    if (p->dm != 0.0) {
        const double *r = T->dcc + (size_t)i * 4 * NC;
        c[C_VG] += p->dm * cubic(r + C_VG, NC, s);
        if (dV) c[C_DVG] += p->dm * cubic(r + C_DVG, NC, s);
    }
    *V = ELEM_POTENTIAL(p, c);
    if (dV) *dV = ELEM_SLOPE(p, c);
    if (p->x) {
        xtab_eval(T, i, s, x, NULL);
        *V += ELEM_POTENTIAL_X(p, x);
        if (dV) *dV += ELEM_SLOPE_X(p, x);
    }
}

static inline int potential(const Table *T, const Par *p, double th, double *V, double *dV)
{
    double s;
    int i = cell_index(T, th, &s);
    if (i < 0) return 1;
    potential_at(T, p, i, s, V, dV);
    return 0;
}

/* the friction moment T_fr at th (the lumped friction and the strut's F_R |l'|): what holds
 * a lane at rest there; 1 outside the table */
static int friction_moment(const Table *T, const Par *p, double th, double *Tfr)
{
    double v[NC];
    if (p->FR == 0.0) { *Tfr = p->Tf; return 0; }
    if (tab_eval(T, p, th, v, NULL)) return 1;
    *Tfr = ELEM_FRICTION_MOMENT(p, v);
    return 0;
}

/* V and its slope at node j = 0..ncell (the pieces' end values) */
static inline void node_potential(const Table *T, const Par *p, int j, double *V, double *dV)
{
    if (j < T->ncell) potential_at(T, p, j, 0.0, V, dV);
    else potential_at(T, p, T->ncell - 1, 1.0, V, dV);
}

/* solve the n x n system a x = r in place (partial pivoting); returns 1 if singular */
static int gauss(int n, double a[2 * SMAX][2 * SMAX], double *r)
{
    for (int col = 0; col < n; col++) {
        int piv = col;
        for (int i = col + 1; i < n; i++)
            if (fabs(a[i][col]) > fabs(a[piv][col])) piv = i;
        if (a[piv][col] == 0.0) return 1;
        if (piv != col) {
            for (int j = 0; j < n; j++) { double t = a[col][j]; a[col][j] = a[piv][j]; a[piv][j] = t; }
            double t = r[col]; r[col] = r[piv]; r[piv] = t;
        }
        for (int i = col + 1; i < n; i++) {
            double f = a[i][col] / a[col][col];
            for (int j = col; j < n; j++) a[i][j] -= f * a[col][j];
            r[i] -= f * r[col];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        for (int j = i + 1; j < n; j++) r[i] -= a[i][j] * r[j];
        r[i] /= a[i][i];
    }
    return 0;
}

static inline int rhs_fast(const Table *T, const Par *p, double th, double thd, double *thdd);

/* one step of length h from (th, thd); returns a status (0 ok) */
static int step(const Table *T, const Method *m, const Par *p, double h,
                double th, double thd, double *th1, double *thd1)
{
    int s = m->s;
    if (m->kind == 2) { /* symplectic Euler: velocity first */
        double a;
        if (rhs(T, p, th, thd, &a, NULL)) return S_RANGE;
        *thd1 = thd + h * a;
        *th1 = th + h * *thd1;
        return 0;
    }
    double K0[SMAX], K1[SMAX]; /* stage derivatives of theta and theta' */
    if (m->kind == 0) {
        for (int i = 0; i < s; i++) {
            double y0 = th, y1 = thd;
            for (int j = 0; j < i; j++) { y0 += h * m->A[i][j] * K0[j]; y1 += h * m->A[i][j] * K1[j]; }
            K0[i] = y1;
            if (rhs_fast(T, p, y0, y1, &K1[i])) return S_RANGE; /* (= rhs(), 6 of the 8 pieces) */
        }
    } else { /* implicit: Newton on the stage derivatives, full Jacobian */
        double a0;
        if (rhs(T, p, th, thd, &a0, NULL)) return S_RANGE;
        for (int i = 0; i < s; i++) { K0[i] = thd; K1[i] = a0; }
        int ok = 0;
        for (int it = 0; it < 30; it++) {
            double G[2 * SMAX], Jm[2 * SMAX][2 * SMAX], Ji[SMAX][2];
            for (int i = 0; i < s; i++) {
                double y0 = th, y1 = thd, f1;
                for (int j = 0; j < s; j++) { y0 += h * m->A[i][j] * K0[j]; y1 += h * m->A[i][j] * K1[j]; }
                if (rhs(T, p, y0, y1, &f1, Ji[i])) return S_RANGE;
                G[2 * i] = -(K0[i] - y1);
                G[2 * i + 1] = -(K1[i] - f1);
            }
            for (int i = 0; i < s; i++)
                for (int j = 0; j < s; j++) {
                    double ha = h * m->A[i][j], d = (i == j);
                    /* K0_i - (thd + h a_ij K1_j) ; K1_i - f(y_i) */
                    Jm[2 * i][2 * j] = d;
                    Jm[2 * i][2 * j + 1] = -ha;
                    Jm[2 * i + 1][2 * j] = -ha * Ji[i][0];
                    Jm[2 * i + 1][2 * j + 1] = d - ha * Ji[i][1];
                }
            if (gauss(2 * s, Jm, G)) return S_NEWTON;
            double dn = 0, kn = 0;
            for (int i = 0; i < s; i++) {
                K0[i] += G[2 * i]; K1[i] += G[2 * i + 1];
                dn += fabs(G[2 * i]) + fabs(G[2 * i + 1]) * h;
                kn += fabs(K0[i]) + fabs(K1[i]) * h;
            }
            if (!isfinite(dn)) return S_NONFINITE;
            if (dn <= 1e-14 * (1.0 + kn)) { ok = 1; break; }
        }
        if (!ok) return S_NEWTON;
    }
    double y0 = th, y1 = thd;
    for (int i = 0; i < s; i++) { y0 += h * m->b[i] * K0[i]; y1 += h * m->b[i] * K1[i]; }
    *th1 = y0; *thd1 = y1;
    return 0;
}

/* quantity whose extremum is refined: 0 tip speed tau(th)|th'| (max), 1 theta (min),
 * 2 -theta (min, i.e. the highest angle) */
static int quantity(const Table *T, const Par *p, int which, double th, double thd,
                    double *g, double *dg)
{
    if (which == 1) { *g = th; *dg = thd; return 0; }
    if (which == 2) { *g = -th; *dg = -thd; return 0; }
    double v[NC], dv[NC], a;
    if (tab_eval(T, p, th, v, dv)) return 1;
    if (rhs(T, p, th, thd, &a, NULL)) return 1;
    double sg = thd >= 0 ? 1.0 : -1.0;
    *g = v[C_TAU] * fabs(thd);
    *dg = sg * (dv[C_TAU] * thd * thd + v[C_TAU] * a);
    return 0;
}

/* extremum of a quantity on a step of solved length s in [0, smax] from (th, thd):
 * root of its time derivative, bracketed by sampling, then Illinois false position. */
static int refine_extremum(const Table *T, const Method *m, const Par *p, int which,
                           double th, double thd, double smax, double *gbest)
{
    double sa = 0.0, ga, da;
    if (quantity(T, p, which, th, thd, &ga, &da)) return 1;
    double prev_s = 0.0, prev_d = da, lo = -1, hi = -1, dlo = 0, dhi = 0;
    const int NS = 4;
    for (int q = 1; q <= NS; q++) {
        double s1 = smax * q / NS, y0, y1, g1, d1;
        if (step(T, m, p, s1, th, thd, &y0, &y1)) return 1;
        if (quantity(T, p, which, y0, y1, &g1, &d1)) return 1;
        if ((which == 0 && g1 > *gbest) || (which != 0 && g1 < *gbest)) *gbest = g1;
        if ((prev_d > 0) != (d1 > 0)) { lo = prev_s; hi = s1; dlo = prev_d; dhi = d1; break; }
        prev_s = s1; prev_d = d1;
    }
    (void)sa;
    if (lo < 0) return 0;
    int side = 0;
    for (int it = 0; it < 60 && hi - lo > 1e-15 * (1.0 + smax); it++) {
        double sm = lo - dlo * (hi - lo) / (dhi - dlo);
        if (!(sm > lo && sm < hi)) sm = 0.5 * (lo + hi);
        double y0, y1, gm, dm;
        if (step(T, m, p, sm, th, thd, &y0, &y1)) return 1;
        if (quantity(T, p, which, y0, y1, &gm, &dm)) return 1;
        if ((which == 0 && gm > *gbest) || (which != 0 && gm < *gbest)) *gbest = gm;
        if (dm == 0.0) break;
        if ((dm > 0) == (dlo > 0)) { lo = sm; dlo = dm; if (side == -1) dhi *= 0.5; side = -1; }
        else { hi = sm; dhi = dm; if (side == 1) dlo *= 0.5; side = 1; }
    }
    return 0;
}

/* extremes of the tabulated spring length over [a, b] (exact for the interpolant) */
static void l_extremes(const Table *T, double a, double b, double *lmin, double *lmax)
{
    double v[NC];
    double ends[2] = {a, b};
    *lmin = INFINITY; *lmax = -INFINITY;
    for (int e = 0; e < 2; e++)
        if (!tab_eval(T, NULL, ends[e], v, NULL)) {
            if (v[C_L] < *lmin) *lmin = v[C_L];
            if (v[C_L] > *lmax) *lmax = v[C_L];
        }
    int i0 = (int)floor((a - T->lo) / T->h), i1 = (int)floor((b - T->lo) / T->h);
    if (i0 < 0) i0 = 0;
    if (i1 > T->ncell - 1) i1 = T->ncell - 1;
    /* with the cell ranges, only the cells where l' may vanish (the others: l monotone) */
    int nc = T->crit ? T->ncrit : i1 - i0 + 1, c0 = 0;
    while (T->crit && c0 < nc && T->crit[c0] < i0) c0++;
    for (int c = c0; c < nc; c++) {
        int i = T->crit ? T->crit[c] : i0 + c;
        if (i > i1) break;
        double q[4] = {CQ(T->cc, i, 0, C_L), CQ(T->cc, i, 1, C_L), CQ(T->cc, i, 2, C_L),
                       CQ(T->cc, i, 3, C_L)};
        cubic_extremes(q, i, T, a, b, lmin, lmax);
    }
}

/* the roots r (0, 1 or 2; returned) of the derivative q1 + 2 q2 s + 3 q3 s^2 of the cubic q */
static inline int cubic_crit(const double *q, double r[2])
{
    double A = 3 * q[3], B = 2 * q[2], C = q[1];
    int nr = 0;
    if (fabs(A) < 1e-300) { if (B != 0) r[nr++] = -C / B; }
    else {
        double D = B * B - 4 * A * C;
        if (D >= 0) {
            double sq = sqrt(D);
            r[nr++] = (-B + sq) / (2 * A); r[nr++] = (-B - sq) / (2 * A);
        }
    }
    return nr;
}

/* the interior extremes of the cubic q (the pieces of l on cell i: the table's, or a row's
 * own, PER-ROW ATTACHMENT POINTS) within [a, b] into lmin, lmax */
static void cubic_extremes(const double *q, int i, const Table *T, double a, double b,
                           double *lmin, double *lmax)
{
    double r[2];
    int nr = cubic_crit(q, r);
    for (int j = 0; j < nr; j++) {
        double th = T->lo + (i + r[j]) * T->h;
        if (r[j] < 0 || r[j] > 1 || th < a || th > b) continue;
        double l = cubic(q, 1, r[j]);
        if (l < *lmin) *lmin = l;
        if (l > *lmax) *lmax = l;
    }
}

/* ---- early exit: what the rest of a stroke can still reach ------------------------- */

/* range of the cubic q0 + q1 s + q2 s^2 + q3 s^3 over [s0, s1] (ends and interior extrema) */
static void cubic_range(const double *q, double s0, double s1, double *lo, double *hi)
{
    double a = cubic(q, 1, s0);
    double b = cubic(q, 1, s1);
    *lo = a < b ? a : b; *hi = a < b ? b : a;
    double r[2];
    int nr = cubic_crit(q, r);
    for (int j = 0; j < nr; j++) {
        if (!(r[j] > s0 && r[j] < s1)) continue;
        double v = cubic(q, 1, r[j]);
        if (v < *lo) *lo = v;
        if (v > *hi) *hi = v;
    }
}

/* the cubic of coefficient j in cell i for the row p (mass-corrected) */
static inline void piece(const Table *T, const Par *p, int i, int j, double *q)
{
    if ((p->ps && (j == C_L || j == C_DL)) || (p->pd && j == C_DD)) { /* the row's own */
        const double *b = pt_piece(T, p, i);
        for (int e = 0; e < 4; e++) q[e] = b[e * NC + j];
        return;
    }
    for (int e = 0; e < 4; e++) q[e] = CQ(T->cc, i, e, j);
    if (j < NMASS && p->dm != 0.0)
        for (int e = 0; e < 4; e++) q[e] += p->dm * CQ(T->dcc, i, e, j);
}

/* Is 2 tau^2 (Eh - V) / M <= tg (the squared tip speed, tau |th'|) and 2 (Eh - V) / M <= tv
 * (the squared |th'|) wherever V <= Eh on cell i, s in [s0, s1]? A rigorous
 * bound from the ranges of the cubic pieces, with V bounded below both by
 * min Vg + k d^2 / 2 (d: distance of l0 from the range of l) and by the mean value theorem,
 * V(mid) - max |dV| * half width (dV = dVg + k (l - l0) dl over the ranges: tight near a
 * well's bottom, where the two terms of V vary in opposite senses); halved where it is too
 * coarse. Returns 0 as soon as a point exceeds the target (or the work budget is spent),
 * 1 if the bound holds, 2 if V > Eh on the whole piece (unreachable). */
static int speed_piece_ok(const Table *T, const Par *p, int i, double s0, double s1, double Eh,
                          double tg, double tv, int depth, int *budget)
{
    if (--*budget < 0) return 0;
    double q[4], glo, ghi, llo, lhi, dglo, dghi, dllo, dlhi, tlo, thi, Mlo, Mhi, v[NC];
    double x[NX] = {0};
    const double *R = depth == 0 && p->dm == 0.0 && !p->ps && T->rng
                      ? T->rng + (size_t)i * NRNG : NULL; /* (the table's own l, dl) */
    /* (with R, the middle values are the whole cell's: its middle is where x is read) */
    double sm = R ? 0.5 : 0.5 * (s0 + s1), hw = 0.5 * (s1 - s0) * T->h;
    if (R) { /* the whole cell's precomputed ranges (a superset of [s0, s1]) */
        glo = R[R_VG]; ghi = R[R_VG + 1]; llo = R[R_L]; lhi = R[R_L + 1];
        dglo = R[R_DVG]; dghi = R[R_DVG + 1]; dllo = R[R_DL]; dlhi = R[R_DL + 1];
        tlo = R[R_TAU]; thi = R[R_TAU + 1]; Mlo = R[R_M]; Mhi = R[R_M + 1];
        v[C_VG] = R[R_MID]; v[C_L] = R[R_MID + 1]; v[C_TAU] = R[R_MID + 2]; v[C_M] = R[R_MID + 3];
        hw = 0.5 * T->h;
    } else {
        if (tab_eval(T, p, T->lo + (i + sm) * T->h, v, NULL)) return 0;
        piece(T, p, i, C_VG, q); cubic_range(q, s0, s1, &glo, &ghi);
        piece(T, p, i, C_DVG, q); cubic_range(q, s0, s1, &dglo, &dghi);
        piece(T, p, i, C_L, q); cubic_range(q, s0, s1, &llo, &lhi);
        piece(T, p, i, C_DL, q); cubic_range(q, s0, s1, &dllo, &dlhi);
        piece(T, p, i, C_TAU, q); cubic_range(q, s0, s1, &tlo, &thi);
        piece(T, p, i, C_M, q); cubic_range(q, s0, s1, &Mlo, &Mhi);
    }
    /* V at the middle, and the springs' least potential and slope range over the piece */
    double Vm = ELEM_POTENTIAL(p, v);
    if (p->x) { xtab_eval(T, i, sm, x, NULL); Vm += ELEM_POTENTIAL_X(p, x); }
    double Vsp, sslo, sshi;
    law_preloaded_bounds(p->k, p->l0, p->F, llo, lhi, dllo, dlhi, &Vsp, &sslo, &sshi);
    if (p->G != 0.0) {
        double Vg, gslo, gshi;
        law_gas_bounds(p->G, p->gb, p->l0, llo, lhi, dllo, dlhi, &Vg, &gslo, &gshi);
        Vsp += Vg; sslo += gslo; sshi += gshi;
    }
    double V1 = glo + Vsp;
    double slo = dglo + sslo, shi = dghi + sshi;
    if (p->x) elem_bounds_x(T->xcc, p, i, s0, s1, &V1, &slo, &shi);
    double smax = MAX2(fabs(slo), fabs(shi));
    double V2 = Vm - smax * hw;
    double Vlow = MAX2(V1, V2);
    Vlow -= 1e-13 * (fabs(Vlow) + fabs(Eh)); /* rounding of the bound itself */
    if (Vlow > Eh) return 2; /* unreachable */
    (void)Mhi;
    if (!(Mlo > 0)) return 0;
    double t2 = thi > -tlo ? thi * thi : tlo * tlo, w = 2.0 * (Eh - Vlow) / Mlo;
    if (t2 * w <= tg && w <= tv) return 1;
    if (R && !(s0 == 0.0 && s1 == 1.0)) /* (the cell's middle may lie outside [s0, s1]) */
        return speed_piece_ok(T, p, i, s0, s1, Eh, tg, tv, depth + 1, budget);
    double wm = 2.0 * (Eh - Vm) / v[C_M];
    if (v[C_TAU] * v[C_TAU] * wm > tg || wm > tv) return 0; /* reachable: not final */
    if (depth >= 30) return 0;
    return speed_piece_ok(T, p, i, s0, sm, Eh, tg, tv, depth + 1, budget)
           && speed_piece_ok(T, p, i, sm, s1, Eh, tg, tv, depth + 1, budget);
}

/* Can the lid, from th with energy at most Eh and never leaving [a, b], reach a tip speed
 * above `peak` or a theta' above `thd_max`? 1 if not (both are final). The cells are
 * visited outwards from th's until a cell lies wholly above Eh (the component of
 * {V <= Eh} cannot cross it). */
static int speed_bound_ok(const Table *T, const Par *p, double th, double a, double b,
                          double Eh, double peak, double thd_max)
{
    double xa = (a - T->lo) * T->inv_h, xb = (b - T->lo) * T->inv_h, x = (th - T->lo) * T->inv_h;
    if (!(xa >= 0 && xb <= T->ncell && x >= xa && x <= xb)) return 0;
    int i0 = (int)floor(xa), i1 = (int)floor(xb), ith = (int)floor(x), budget = 4000;
    if (i1 > T->ncell - 1) i1 = T->ncell - 1;
    if (ith > i1) ith = i1;
    if (!(thd_max > 0)) return 0;
    /* (1 - 1e-10): a margin for the rounding of tau |th'| and th' from the energy */
    double tg = peak * peak * (1.0 - 1e-10), tv = thd_max * thd_max * (1.0 - 1e-10);
    for (int dir = -1; dir <= 1; dir += 2)
        for (int i = dir < 0 ? ith : ith + 1; dir < 0 ? i >= i0 : i <= i1; i += dir) {
            double s0 = xa - i > 0 ? xa - i : 0.0, s1 = xb - i < 1 ? xb - i : 1.0;
            if (s1 < s0) continue;
            int r = speed_piece_ok(T, p, i, s0, s1, Eh, tg, tv, 0, &budget);
            if (r == 0) return 0;
            if (r == 2 && i != ith) break;
        }
    return 1;
}

/* root of the tabulated slope dV in [a, b] by bisection, given its signs at the ends */
static double slope_root(const Table *T, const Par *p, double a, double b, double fa)
{
    for (int it = 0; it < 200 && b - a > 4e-16 * (1.0 + fabs(a)); it++) {
        double mid = 0.5 * (a + b), V, dV;
        if (potential(T, p, mid, &V, &dV)) break;
        if (dV == 0.0) return mid;
        if ((dV > 0) == (fa > 0)) { a = mid; fa = dV; } else b = mid;
    }
    return 0.5 * (a + b);
}

static inline double node_at(const Table *T, int j) { return T->lo + j * T->h; }

/* extremum of V over [a, b] (sgn +1: max, -1: min): the ends, and every root of the
 * tabulated slope dV where it changes sign the right way between consecutive nodes
 * (bisection to full precision). *at_end: 1 if it is at a, 2 at b, else 0. */
static double v_extremum(const Table *T, const Par *p, double a, double b, int sgn,
                         double *Vbest, int *at_end)
{
    double Va, Vb, dVa, dVb;
    if (potential(T, p, a, &Va, &dVa) || potential(T, p, b, &Vb, &dVb)) {
        *at_end = 1; *Vbest = NAN; return a;
    }
    double best = sgn * Va, arg = a;
    int end = 1;
    if (sgn * Vb > best) { best = sgn * Vb; arg = b; end = 2; }
    int j0 = (int)ceil((a - T->lo) * T->inv_h), j1 = (int)floor((b - T->lo) * T->inv_h);
    double x0 = a, d0 = dVa;
    for (int j = j0; j <= j1 + 1; j++) {
        double x1 = j <= j1 ? node_at(T, j) : b, V1, d1;
        if (x1 <= x0) continue;
        if (x1 > b) x1 = b;
        if (x1 == b) d1 = dVb;
        else if (j >= 0 && j <= T->ncell) node_potential(T, p, j, &V1, &d1);
        else break;
        if (sgn * d0 > 0 && sgn * d1 < 0) {
            double r = slope_root(T, p, x0, x1, d0), V;
            if (!potential(T, p, r, &V, NULL) && sgn * V > best) {
                best = sgn * V; arg = r; end = 0;
            }
        }
        x0 = x1; d0 = d1;
        if (x1 >= b) break;
    }
    *at_end = end;
    *Vbest = sgn * best;
    return arg;
}

/* Why the lid at th with energy (plus margin) Eh cannot reach thc, if it cannot. The well
 * [a, b] of {V <= Eh} around th is found on the nodes between cap_lo >= thc and cap_hi
 * (an end is a cap whose V is above Eh, else the first node above Eh); its bottom th_eq is
 * the stable equilibrium the lid settles at. Below the well, V rises over the hill that
 * stops the lid: if it rises all the way to the rim, the lid is held open (R_HELD,
 * *theta = th_eq); else the top of that hill is the barrier (R_BARRIER, *theta = its
 * top). R_NONE: the energy still reaches the rim. */
static int classify(const Table *T, const Par *p, double th, double Eh, double thc,
                    double cap_lo, double cap_hi, double *theta)
{
    double V;
    int j = (int)floor((th - T->lo) * T->inv_h);
    double a = cap_lo, b = cap_hi;
    for (int jj = j; jj >= 0; jj--) { /* down to the first node above Eh */
        double x = node_at(T, jj);
        if (x <= cap_lo || x > th) { if (x <= cap_lo) break; continue; }
        node_potential(T, p, jj, &V, NULL);
        if (V > Eh) { a = x; break; }
    }
    if (a == cap_lo && (potential(T, p, cap_lo, &V, NULL) || !(V > Eh))) return R_NONE;
    for (int jj = j + 1; jj <= T->ncell; jj++) {
        double x = node_at(T, jj);
        if (x >= cap_hi) break;
        if (x < th) continue;
        node_potential(T, p, jj, &V, NULL);
        if (V > Eh) { b = x; break; }
    }
    if (th < a) a = th; /* (th lies in the well; guard against the rounding of the nodes) */
    if (th > b) b = th;
    double Veq;
    int end;
    *theta = v_extremum(T, p, a, b, -1, &Veq, &end);
    /* climb the hill below the well, node by node, while V keeps rising */
    double xp = a, Vp, dp;
    if (a <= thc || potential(T, p, a, &Vp, &dp)) return R_HELD;
    for (int jj = (int)ceil((a - T->lo) * T->inv_h) - 1; jj >= 0; jj--) {
        double x = node_at(T, jj), Vj, dj;
        if (x >= xp) continue;
        int rim = x <= thc;
        if (rim) x = thc;
        if (potential(T, p, x, &Vj, &dj)) return R_HELD;
        if (Vj < Vp) { /* xp is the highest point so far: the top is on one of its sides */
            double top = xp;
            if (dj > 0 && dp < 0) top = slope_root(T, p, x, xp, dj);
            else if (dp > 0) { /* above xp, towards the well */
                double x2 = xp + T->h, V2, d2;
                if (x2 > a) x2 = a;
                if (x2 > xp && !potential(T, p, x2, &V2, &d2) && d2 < 0)
                    top = slope_root(T, p, xp, x2, dp);
            }
            *theta = top;
            return R_BARRIER;
        }
        if (rim) return R_HELD; /* rising all the way to the rim */
        xp = x; Vp = Vj; dp = dj;
    }
    return R_HELD;
}

/* ---- the stroke loop ----------------------------------------------------------------
 * A stroke is a small state machine (Lane). Several strokes are advanced in lockstep
 * ("lanes"): their RK stages are independent, so the CPU overlaps the table look-ups and
 * divisions of one lane with those of the others instead of waiting on one dependent
 * chain. Each lane's bookkeeping after a step (event, peak, energy) is the scalar code of
 * one stroke (on the vector path its common case in vector form, see SPEED at the top); a
 * finished lane is refilled with the next design. Results do not depend on
 * the lane count. The method's first explicit stage at a node is the theta'' already
 * computed there (FSAL), and the tip speed, its rate, theta'' and the energy at a node
 * come from one table look-up. */
typedef struct {
    Par p;
    double e_tol, *out;
    double t, th, thd, th_min, th_max, thp, thdp, hp; /* hp: length of the previous step */
    double gp, g, dg, a, peak, E0, Emax;      /* tip speed at previous/current node, ...  */
    double thd_max;                           /* max theta' over the nodes after t = 0 */
    double E, Vlo, Vhi;         /* energy at the node, V(th_min), V(th_max) */
    double gain, floor_, t_max, dt, inv_dt; /* largest energy gain of a step so far, ... */
    double stop_theta;
    long n, nt, traj_cap;
    double *traj;
    int status, early, wait, reason;
    int early_req; /* the early exit was asked for (it applies once the row dissipates) */
    long nev;      /* crossings of the end damper's angle so far */
} Lane;

/* theta'', tip speed g = tau |th'|, its rate dg, the energy and the potential at a node:
 * one look-up */
static inline int node_eval(const Table *T, const Par *p, double th, double thd,
                            double *a, double *g, double *dg, double *E, double *V)
{
    double s;
    int i = cell_index(T, th, &s);
    if (i < 0) return 1;
    const double *q = T->cc + (size_t)i * 4 * NC;
    double M = cubic(q + C_M, NC, s), dM = cubic(q + C_DM, NC, s), Vg = cubic(q + C_VG, NC, s),
           dVg = cubic(q + C_DVG, NC, s), l = cubic(q + C_L, NC, s), dl = cubic(q + C_DL, NC, s),
           dd = cubic(q + C_DD, NC, s), tau = cubic(q + C_TAU, NC, s);
    if (p->dm != 0.0) {
        const double *r = T->dcc + (size_t)i * 4 * NC;
        M += p->dm * cubic(r + C_M, NC, s); dM += p->dm * cubic(r + C_DM, NC, s);
        Vg += p->dm * cubic(r + C_VG, NC, s); dVg += p->dm * cubic(r + C_DVG, NC, s);
    }
    double dtau = dcubic(q + C_TAU, NC, s, T->inv_h);
    double c[NC], x[NX];
    c[C_VG] = Vg; c[C_DVG] = dVg; c[C_L] = l; c[C_DL] = dl; c[C_DD] = dd;
    if (p->ps | p->pd) pts_eval(T, p, i, s, c, NULL);
    double damp = ELEM_DAMPING(p, c), slope = ELEM_SLOPE(p, c);
    double Vn = ELEM_POTENTIAL(p, c), En = ELEM_ENERGY(p, c, 0.5 * M * thd * thd);
    if (p->x) {
        xtab_eval(T, i, s, x, NULL);
        slope += ELEM_SLOPE_X(p, x); damp += ELEM_DAMPING_X(p, x);
        Vn += ELEM_POTENTIAL_X(p, x); En += ELEM_POTENTIAL_X(p, x);
    }
    if (p->e) damp += ELEM_DAMPING_E(p);
    damp = ELEM_ONE_WAY(p, thd, damp);
    double N = -slope - 0.5 * dM * thd * thd - damp * thd;
    if (ELEM_STICKS(p)) N -= ELEM_FRICTION(p, c);
    double acc = N / M;
    double sg = thd >= 0 ? 1.0 : -1.0;
    *a = acc;
    *g = tau * fabs(thd);
    *dg = sg * (dtau * thd * thd + tau * acc);
    *E = En;
    *V = Vn;
    return 0;
}

static inline void lane_record(Lane *L)
{
    if (L->traj && L->nt < L->traj_cap) {
        L->traj[3 * L->nt] = L->t; L->traj[3 * L->nt + 1] = L->th; L->traj[3 * L->nt + 2] = L->thd;
        L->nt++;
    }
}

/* A spring of a kind (s > 0 extension: valid while l >= l0; s < 0 compression: l <= l0)
 * outside that range at every angle from the rim thc to the release th0 is an invalid
 * design whatever its stroke does, as the reference has it: the stroke is not integrated
 * (1: the lane is over, not closed, having "visited" [thc, th0], whose spring extremes
 * lane_finish reports; no step taken: peak 0, 0 steps, stop_time 0). Decided with a
 * margin of 1e-6 max(|l|, 1) beyond the rounding scale the statics test with, so every
 * such row is out of range there too. */
static int lane_invalid_throughout(const Table *T, Lane *L, double s, double th0, double thc)
{
    if (!(th0 > thc) || (L->p.ps && !T->pcc)) return 0;
    double lmin, lmax;
    if (L->p.ps) l_extremes_pts(T, &L->p, thc, th0, &lmin, &lmax);
    else l_extremes(T, thc, th0, &lmin, &lmax);
    double margin = 1e-6 * MAX2(MAX2(fabs(lmin), fabs(lmax)), 1.0);
    if (!(s < 0 ? lmin > L->p.l0 + margin || lmax < L->p.lc - margin
                : lmax < L->p.l0 - margin)) return 0;
    L->th_min = thc; L->th_max = th0;
    L->E0 = L->Emax = 0.0; L->thd_max = 0.0;
    lane_record(L); /* (a trajectory of its release alone) */
    return 1;
}

/* start a stroke from rest at th0 (the rim at thc); returns 1 if it is already over (not
 * tabulated) */
static int lane_start(const Table *T, Lane *L, const double *d, int ncol, double *out,
                      double th0, double thc, double dt, double t_max, int early,
                      double *traj, long traj_cap)
{
    ELEM_READ(&L->p, d, T);
    ELEM_ENGAGE_START(&L->p, th0, thc);
    pts_read(&L->p, d, ncol);
    L->e_tol = d[D_ENERGY_TOL];
    L->p.dm = 0.0;
    if (ncol > D_LID_MASS && isfinite(d[D_LID_MASS]) && d[D_LID_MASS] != T->m0) L->p.dm = d[D_LID_MASS] - T->m0;
    L->out = out;
    L->t = 0.0; L->th = th0; L->thd = 0.0; L->th_min = th0; L->th_max = th0;
    L->thp = th0; L->thdp = 0.0; L->hp = 0.0;
    L->gp = 0.0; L->g = 0.0; L->dg = 0.0; L->peak = 0.0; L->a = 0.0;
    L->n = 0; L->nt = 0; L->traj = traj; L->traj_cap = traj_cap; L->thd_max = -INFINITY;
    L->status = S_OPEN; L->reason = R_NONE; L->stop_theta = NAN; L->wait = 0;
    L->gain = 0.0; L->t_max = t_max; L->dt = dt; L->inv_dt = 1.0 / dt;
    /* the energy rule needs dissipation (c dd + c_rot > 0 on the stroke; an end damper from
     * its first engagement on: lane_engage) */
    L->early_req = early; L->nev = 0;
    L->early = early && ELEM_DISSIPATES(&L->p) && ELEM_DAMPERS_VALID(&L->p)
               && !ELEM_STICKS(&L->p);
    for (int j = 0; j < NOUT; j++) out[j] = NAN;
    if (d[D_SPRING_KIND] != 0.0 && lane_invalid_throughout(T, L, d[D_SPRING_KIND], th0, thc)) return 1;
    if (L->p.eg) { out[O_ENGAGE_TIME] = 0.0; out[O_ENGAGE_THETA_DOT] = 0.0; } /* released engaged, at rest */
    lane_record(L);
    double E0, V0;
    if (ELEM_STICKS(&L->p)) { /* released from rest: it moves only if |V'| exceeds T_fr */
        double Vr, dVr, Tfr;
        if ((L->p.dm != 0.0 && !T->dcc) || (L->p.x && !T->xcc) || ((L->p.ps | L->p.pd) && !T->pcc)
            || potential(T, &L->p, th0, &Vr, &dVr) || friction_moment(T, &L->p, th0, &Tfr)) {
            L->E0 = L->Emax = NAN; L->status = S_RANGE; return 1;
        }
        if (fabs(dVr) <= Tfr) {
            L->E0 = L->Emax = L->E = Vr; L->Vlo = L->Vhi = Vr;
            L->reason = R_STUCK; L->stop_theta = th0;
            return 1;
        }
        L->p.fs = dVr < 0 ? 1.0 : -1.0;     /* it moves the way -V' drives it */
    }
    if ((L->p.dm != 0.0 && !T->dcc) || (L->p.x && !T->xcc) || ((L->p.ps | L->p.pd) && !T->pcc)
        || node_eval(T, &L->p, th0, 0.0, &L->a, &L->g, &L->dg, &E0, &V0) || !isfinite(E0)) {
        L->E0 = L->Emax = NAN; L->status = S_RANGE; return 1;
    }
    L->E0 = L->Emax = L->E = E0;
    L->Vlo = L->Vhi = V0;
    { /* rounding scale of the energy: the size of its terms */
        double v[NC] = {0}, x[NX] = {0};
        tab_eval_x(T, &L->p, th0, v, NULL, x, NULL);
        double size = ELEM_SIZE(&L->p, v);
        if (L->p.x) size += ELEM_SIZE_X(&L->p, x);
        L->floor_ = 1e-12 * (size + fabs(E0));
    }
    return 0;
}

static void lane_finish(const Table *T, Lane *L, double thc, double t_max)
{
    double *out = L->out;
    out[O_STATUS] = L->status;
    out[O_PEAK_TIP_SPEED] = L->peak;
    out[O_STEPS] = (double)L->n;
    out[O_ENERGY_RISE] = L->Emax - L->E0;
    out[O_THETA_MIN] = L->th_min;
    out[O_THETA_DOT_MAX] = L->thd_max;
    out[O_THETA_MAX] = L->th_max;
    out[O_STOP_TIME] = L->t;
    if (L->status == S_CLOSED || L->status == S_OPEN) {
        double lmin, lmax;
        if (L->p.ps) l_extremes_pts(T, &L->p, L->th_min, L->th_max, &lmin, &lmax);
        else l_extremes(T, L->th_min, L->th_max, &lmin, &lmax);
        out[O_MIN_SPRING_LENGTH] = lmin; out[O_MAX_SPRING_LENGTH] = lmax;
    }
    if (L->status == S_OPEN && L->reason == R_NONE && L->t >= t_max * (1 - 1e-12)) {
        /* ran to t_max: say why it is open, if the energy (with its margin) decides it */
        double th = NAN, margin = 2.0 * L->gain + L->floor_;
        L->reason = classify(T, &L->p, L->th, L->E + margin, thc, thc, T->lo + T->ncell * T->h,
                             &th);
        L->stop_theta = th;
    }
    out[O_STOP_REASON] = L->reason;
    out[O_STOP_THETA] = L->reason ? L->stop_theta : NAN;
    if (L->status != S_CLOSED) { out[O_CLOSING_TIME] = NAN; out[O_IMPACT_THETA_DOT] = NAN; out[O_IMPACT_TIP_SPEED] = NAN; }
}

/* after an accepted node: can the rest of the stroke still change anything? (see top)
 * Called when E < V(th_min), V(th_max) or at a fixed point. */
__attribute__((noinline)) static int lane_try_exit(const Table *T, Lane *L, double thc,
                                                   double th_prev, double thd_prev)
{
    if (L->th == th_prev && L->thd == thd_prev) {
        /* a fixed point of the step map (at rest): every further full step returns the same
         * state and changes nothing but the clock, so those steps are skipped; a last,
         * shorter step to t_max (if any) is taken as usual */
        if (L->hp == L->dt)
            for (;;) {
                double h = L->dt < L->t_max - L->t ? L->dt : L->t_max - L->t;
                if (!(L->t < L->t_max && h > 1e-15 * L->t_max) || h != L->dt) break;
                L->t += h; L->n++;
                lane_record(L);
            }
        return 0;
    }
    /* what the method may still gain: twice its largest gain per step so far for each
     * step left, plus the rounding of E */
    double left = (L->t_max - L->t) * L->inv_dt + 1.0;
    double Eh = L->E + 2.0 * left * L->gain + L->floor_;
    if (!(Eh < L->Vlo && Eh < L->Vhi)) return 0; /* a visited end is still reachable */
    if (L->wait > 0) { L->wait--; return 0; }
    if (!speed_bound_ok(T, &L->p, L->th, L->th_min, L->th_max, Eh, L->peak, L->thd_max)) {
        L->wait = 8; /* the peak may still grow: look again a few steps later */
        return 0;
    }
    double th = NAN;
    L->reason = classify(T, &L->p, L->th, Eh, thc, L->th_min, L->th_max, &th);
    if (L->reason == R_NONE) L->reason = R_HELD, th = L->th; /* (cannot happen: th_min > thc) */
    L->stop_theta = th;
    return 1;
}

/* A lane with dry friction came to rest inside its step of length h (theta' changed sign
 * against the friction's direction): the rest is located by a step of solved length, as
 * the closing event (secant on theta'(tau), then bisection), so to the method's order; it
 * is a turning point (an extreme of theta); there the lid sticks unless |V'| > T_f, else it
 * moves on the way -V' drives it, from rest. 1 = the stroke is over (stuck). */
__attribute__((noinline)) static int lane_friction_rest(const Table *T, const Method *m,
                                                        Lane *L, double h, double th1,
                                                        double thd1)
{
    Par *p = &L->p;
    double th = L->th, thd = L->thd, a = 0.0, b = h, y0 = th1, y1 = thd1, tau = h;
    /* theta'(0) has the friction's sign (or is 0: just released), theta'(h) the other */
    double fa = thd != 0.0 ? thd : p->fs * 1e-300, fb = thd1;
    int side = 0;
    for (int it = 0; it < 200 && b - a > 1e-15 * h; it++) { /* Illinois false position */
        tau = a - fa * (b - a) / (fb - fa);
        if (!(tau > a && tau < b)) tau = 0.5 * (a + b);
        if (step(T, m, p, tau, th, thd, &y0, &y1)) { L->status = S_RANGE; return 1; }
        if (y1 == 0.0 || fabs(y1) <= 1e-15 * (1.0 + fabs(thd) + fabs(thd1))) break;
        if ((y1 > 0) == (fa > 0)) { a = tau; fa = y1; if (side == -1) fb *= 0.5; side = -1; }
        else { b = tau; fb = y1; if (side == 1) fa *= 0.5; side = 1; }
    }
    /* a peak of the tip speed before the rest (it falls to 0 there) */
    if (L->n > 1 && L->g >= L->gp && L->g > 0)
        refine_extremum(T, m, p, 0, L->thp, L->thdp, L->hp + tau, &L->peak);
    if (L->g > L->peak) L->peak = L->g;
    double V, dV;
    if (potential(T, p, y0, &V, &dV)) { L->status = S_RANGE; return 1; }
    if (y0 < L->th_min) { L->th_min = y0; L->Vlo = V; }
    if (y0 > L->th_max) { L->th_max = y0; L->Vhi = V; }
    L->t += tau; L->th = y0; L->thd = 0.0;
    L->gp = L->g; L->thp = th; L->thdp = thd; L->hp = tau;
    L->E = V;
    lane_record(L);
    double Tfr;
    if (friction_moment(T, p, y0, &Tfr)) { L->status = S_RANGE; return 1; }
    if (fabs(dV) <= Tfr) { L->reason = R_STUCK; L->stop_theta = y0; return 1; }
    p->fs = dV < 0 ? 1.0 : -1.0;
    double E1, V1;
    if (node_eval(T, p, y0, 0.0, &L->a, &L->g, &L->dg, &E1, &V1)) {
        L->status = S_RANGE; return 1;
    }
    return 0;
}

/* the peak tip speed of a step of length h from (th, thd) that ends at an event, where the
 * tip speed is gi and its rate dgi: the node's, a peak between the previous node and the
 * event (refined), the event's */
ALWAYS void peak_to_event(const Table *T, const Method *m, Lane *L, double th, double thd,
                          double h, double gi, double dgi)
{
    const Par *p = &L->p;
    double g = L->g, dg = L->dg;
    if (g > L->peak) L->peak = g;
    if (L->n > 1 && g >= L->gp && g > gi)
        refine_extremum(T, m, p, 0, L->thp, L->thdp, L->hp + h, &L->peak);
    else if (dg > 0 && dgi < 0)
        refine_extremum(T, m, p, 0, th, thd, h, &L->peak);
    if (gi > L->peak) L->peak = gi;
}

/* the turning points inside a step of length h from (th, thd) to (th1, thd1): the lowest
 * angle where the lane turned back, the highest where it turned down (refined), into its
 * visited range with their potential */
ALWAYS void step_turns(const Table *T, const Method *m, Lane *L, double th, double thd,
                       double th1, double thd1, double h)
{
    const Par *p = &L->p;
    if (thd < 0 && thd1 >= 0) { /* turned back: lowest angle inside this step */
        double lowest = th1 < th ? th1 : th;
        refine_extremum(T, m, p, 1, th, thd, h, &lowest);
        if (lowest < L->th_min) {
            L->th_min = lowest;
            if (potential(T, p, lowest, &L->Vlo, NULL)) L->Vlo = -INFINITY;
        }
    }
    if (thd > 0 && thd1 <= 0) { /* turned down: highest angle inside this step */
        double neg = -(th1 > th ? th1 : th);
        refine_extremum(T, m, p, 2, th, thd, h, &neg);
        if (-neg > L->th_max) {
            L->th_max = -neg;
            if (potential(T, p, -neg, &L->Vhi, NULL)) L->Vhi = -INFINITY;
        }
    }
}

/* THE END DAMPER'S ENGAGEMENT (an event, as the friction rest and the closing event).
 * The lane's step of length h from (th, thd) to (th1, thd1) crossed theta_e against its
 * state (ELEM_CROSSED: moving down into the damper, or up out of it). Its law changes
 * there, so nothing is integrated across it: the crossing is located by a step of solved
 * length tau (Illinois false position on theta(tau) - theta_e, the flow of the lane's state
 * before the crossing), so to the method's own order; the lane's node moves to (t + tau,
 * theta_e, theta'(tau)) -- the peak tip speed, turning points and visited range of that
 * shorter step as after any step --, its state switches, and it goes on from there with the
 * other law (theta'' and the tip speed's rate at the node are the new law's). The first
 * engagement moving down is the stroke's engage_time / engage_theta_dot. With dry friction a
 * rest may come first in the same step: then it is that event (lane_friction_rest), and the
 * crossing is found by the next step. 1 = the stroke is over (a failure). */
__attribute__((noinline)) static int lane_engage(const Table *T, const Method *m, Lane *L,
                                                 double h, double th1, double thd1)
{
    Par *p = &L->p;
    const double th = L->th, thd = L->thd, the = p->the;
    double a = 0.0, b = h, y0 = th1, y1 = thd1, tau = h;
    /* theta - theta_e: < 0 on the engaged side, >= 0 on the other */
    double fa = th - the, fb = th1 - the;
    if (fa == 0.0) {
        /* the lane sits on theta_e (an earlier crossing) and moves into its side: the root
         * at tau = 0 is not a crossing, the one where it comes back is. An unstable step
         * (an explicit method beyond its stability at a stiff end damper) can return past
         * theta_e at once: taken at 0, that would switch the lane back and forth without
         * time passing. The bracket starts where the step is on the lane's side (halving
         * tau); none (it leaves its side at once): the crossing is at 0 */
        fa = 0.0;
        for (double sh = 0.5 * h; sh > 1e-15 * h; sh *= 0.5) {
            double z0, z1;
            if (step(T, m, p, sh, th, thd, &z0, &z1)) { L->status = S_RANGE; return 1; }
            double r = z0 - the;
            if (p->eg ? r < 0 : r > 0) { a = sh; fa = r; break; }
            b = sh; fb = r; y0 = z0; y1 = z1;
        }
        if (fa == 0.0) { tau = 0.0; y0 = th; y1 = thd; fb = 0.0; }
        else tau = b;
    }
    int side = 0;
    if (fb != 0.0) /* (0: theta_e is reached at b itself: the crossing is there) */
        for (int it = 0; it < 200 && b - a > 1e-15 * h; it++) {
            tau = a - fa * (b - a) / (fb - fa);
            if (!(tau > a && tau < b)) tau = 0.5 * (a + b);
            if (step(T, m, p, tau, th, thd, &y0, &y1)) { L->status = S_RANGE; return 1; }
            double r = y0 - the;
            if (r == 0.0 || fabs(r) <= 1e-15 * (1.0 + fabs(the))) break;
            if ((r > 0) == (fa > 0)) { a = tau; fa = r; if (side == -1) fb *= 0.5; side = -1; }
            else { b = tau; fb = r; if (side == 1) fa *= 0.5; side = 1; }
        }
    /* an event of no length, again and again, would never end: a lane that crosses more
     * often than it has steps is unstable (an explicit method at a stiff end damper) */
    if (++L->nev > (long)(L->t_max * L->inv_dt) + 64) { L->status = S_UNSTABLE; return 1; }
    if (!isfinite(y0) || !isfinite(y1)) { L->status = S_NONFINITE; return 1; }
    /* a rest of dry friction first: the lane no longer moves its friction's way there */
    if (ELEM_STICKS(p) && thd1 * p->fs < 0 && !(y1 * p->fs > 0))
        return lane_friction_rest(T, m, L, h, th1, thd1);
    /* the tip speed at the crossing and its rate on the side of the step: a peak between
     * the previous node and the crossing (as at the closing event) */
    double gi, dgi;
    if (quantity(T, p, 0, the, y1, &gi, &dgi)) { L->status = S_RANGE; return 1; }
    peak_to_event(T, m, L, th, thd, tau, gi, dgi);
    /* a turning point inside the shorter step (as after a full step) */
    step_turns(T, m, L, th, thd, the, y1, tau);
    /* the switch: engaged moving into the damper, released moving out */
    int down = !p->eg;
    ELEM_ENGAGE_SWITCH(p);
    double a1, g1, dg1, E1, V1;
    if (node_eval(T, p, the, y1, &a1, &g1, &dg1, &E1, &V1) || !isfinite(E1)) {
        L->status = S_RANGE; return 1;
    }
    if (the < L->th_min) { L->th_min = the; L->Vlo = V1; }
    if (the > L->th_max) { L->th_max = the; L->Vhi = V1; }
    if (y1 > L->thd_max) L->thd_max = y1;
    if (E1 > L->Emax) L->Emax = E1;
    if (E1 - L->E > L->gain) L->gain = E1 - L->E;
    L->t += tau; L->th = the; L->thd = y1;
    if (E1 - L->E0 > L->e_tol) { L->status = S_UNSTABLE; return 1; }
    if (down && isnan(L->out[O_ENGAGE_TIME])) { L->out[O_ENGAGE_TIME] = L->t; L->out[O_ENGAGE_THETA_DOT] = y1; }
    /* the law changed at this node: a maximum of the tip speed is looked for from here on
     * (never by a step across it), as from a node before it */
    L->gp = -INFINITY; L->thp = the; L->thdp = y1; L->hp = 0.0;
    L->g = g1; L->dg = dg1; L->a = a1; L->E = E1;
    lane_record(L);
    /* the energy rule applies from the first engagement of a row whose only damper is this */
    if (!L->early)
        L->early = L->early_req && ELEM_DISSIPATES(p) && ELEM_DAMPERS_VALID(p)
                   && !ELEM_STICKS(p);
    return 0;
}

/* the node quantities of node_eval, computed for all lanes at once (or not: ok = -1) */
typedef struct { double a, g, dg, E, V; int ok; } Node;

/* bookkeeping after a step of length h to (th1, thd1) with step status st; nd: the new
 * node's quantities if already evaluated; 1 = over */
ALWAYS int lane_after_step(const Table *T, const Method *m, Lane *L, double h, double th1,
                           double thd1, int st, double thc, const Node *nd)
{
    const Par *p = &L->p;
    double th = L->th, thd = L->thd;
    L->n++;
    if (st) { L->status = st; return 1; }
    if (!isfinite(th1) || !isfinite(thd1)) { L->status = S_NONFINITE; return 1; }
    /* the end damper's engagement angle crossed inside this step (before the rim, which lies
     * below it): that event first */
    if (ELEM_CROSSED(p, th1)) return lane_engage(T, m, L, h, th1, thd1);
    if (th1 <= thc) { /* closing event inside this step: solve its length */
        double tau = h * (th - thc) / (th - th1), y0 = th1, y1 = thd1;
        int ok = 0;
        for (int it = 0; it < 50; it++) {
            if (step(T, m, p, tau, th, thd, &y0, &y1)) break;
            double r = y0 - thc;
            if (fabs(r) <= 1e-15 * (1.0 + fabs(thc))) { ok = 1; break; }
            double tn = tau - r / y1;
            if (!(tn > 0 && tn <= h)) tn = r > 0 ? 0.5 * (tau + h) : 0.5 * tau;
            if (fabs(tn - tau) <= 1e-16 * h) { tau = tn; ok = 1; break; }
            tau = tn;
        }
        if (!ok) { /* safeguard: bisection on [0, h] */
            double a = 0.0, b = h;
            for (int it = 0; it < 80; it++) {
                tau = 0.5 * (a + b);
                if (step(T, m, p, tau, th, thd, &y0, &y1)) break;
                if (y0 > thc) a = tau; else b = tau;
            }
        }
        double gi, dgi;
        quantity(T, p, 0, thc, y1, &gi, &dgi);
        /* a peak between the previous node and the event? */
        peak_to_event(T, m, L, th, thd, tau, gi, dgi);
        if (y1 > L->thd_max) L->thd_max = y1;
        L->t += tau; L->th = thc; L->thd = y1; L->th_min = thc; L->status = S_CLOSED;
        L->out[O_CLOSING_TIME] = L->t; L->out[O_IMPACT_THETA_DOT] = y1; L->out[O_IMPACT_TIP_SPEED] = gi;
        lane_record(L);
        return 1;
    }
    if (ELEM_STICKS(p) && thd1 * p->fs < 0) /* came to rest inside this step */
        return lane_friction_rest(T, m, L, h, th1, thd1);
    /* the new node: theta'' (the next step's first stage), tip speed, its rate, energy */
    double a1, g1, dg1, E1, V1;
    if (nd && nd->ok >= 0) {
        if (!nd->ok) { L->status = S_RANGE; return 1; }
        a1 = nd->a; g1 = nd->g; dg1 = nd->dg; E1 = nd->E; V1 = nd->V;
    } else if (node_eval(T, p, th1, thd1, &a1, &g1, &dg1, &E1, &V1)) {
        L->status = S_RANGE; return 1;
    }
    /* interior extrema at the node we are leaving (t): tip-speed peak, lowest angle */
    if (L->n > 1 && L->g >= L->gp && L->g > g1)
        refine_extremum(T, m, p, 0, L->thp, L->thdp, L->hp + h, &L->peak);
    if (g1 > L->peak) L->peak = g1;
    step_turns(T, m, L, th, thd, th1, thd1, h);
    if (th1 < L->th_min) { L->th_min = th1; L->Vlo = V1; }
    if (th1 > L->th_max) { L->th_max = th1; L->Vhi = V1; }
    if (thd1 > L->thd_max) L->thd_max = thd1;
    if (!isfinite(E1)) { L->status = S_RANGE; return 1; }
    if (E1 > L->Emax) L->Emax = E1;
    if (E1 - L->E > L->gain) L->gain = E1 - L->E;
    if (E1 - L->E0 > L->e_tol) {
        L->status = S_UNSTABLE; L->t += h; L->th = th1; L->thd = thd1; return 1;
    }
    L->gp = L->g; L->thp = th; L->thdp = thd; L->hp = h;
    L->g = g1; L->dg = dg1; L->a = a1; L->E = E1;
    L->t += h; L->th = th1; L->thd = thd1;
    lane_record(L);
    if (L->early && ((th1 == th && thd1 == thd) || (E1 < L->Vlo && E1 < L->Vhi)))
        return lane_try_exit(T, L, thc, th, thd);
    return 0;
}

/* ---- the lanes as SIMD vectors ------------------------------------------------------
 * Element q of a v4 is lane q. Every operation below is the scalar one of rhs()/node_eval()
 * applied element by element, in the same order, so a lane's numbers are those of a scalar
 * stroke bit for bit; what changes is that the dependent chain of one stage (cell look-up,
 * Horner, division) is shared by the lanes instead of being waited for lane by lane. */

/* lane q's cell of the angles th: its base pointer and local variable s;
 * okm: all bits set in the lanes inside the table (outside: cell 0, the result is
 * discarded) */
ALWAYS void cells4(const Table *T, v4 th, const double **b, v4 *s, v4l *okm)
{
    v4 x = (th - T->lo) * T->inv_h;
    v4 zero = {0.0, 0.0, 0.0, 0.0}, top = zero + (double)T->ncell;
    v4l ok = (x >= zero) & (x <= top);
    v4 xs = (v4)((v4l)x & ok); /* 0 where outside (or NaN): a safe conversion */
    v4i ii = __builtin_convertvector(xs, v4i); /* truncation, as (int) */
    v4i last = {T->ncell - 1, T->ncell - 1, T->ncell - 1, T->ncell - 1};
    v4i over = ii > last;
    ii = (ii & ~over) | (last & over);
    *s = xs - __builtin_convertvector(ii, v4);
    *okm = ok;
    for (int q = 0; q < VW; q++) b[q] = T->cc + (size_t)ii[q] * 4 * NC;
}

#if defined(__clang__) || (defined(__GNUC__) && __GNUC__ >= 12)
#define SHUF(a, b, i, j, k, l) __builtin_shufflevector(a, b, i, j, k, l)
#else
#define SHUF(a, b, i, j, k, l) __builtin_shuffle(a, b, (v4l){i, j, k, l})
#endif

/* rows r[q] (lane q, four coefficients) -> columns c[j] (coefficient j, four lanes) */
ALWAYS void transpose4(const v4 *r, v4 *c)
{
    v4 t0 = SHUF(r[0], r[1], 0, 4, 2, 6), t1 = SHUF(r[0], r[1], 1, 5, 3, 7);
    v4 t2 = SHUF(r[2], r[3], 0, 4, 2, 6), t3 = SHUF(r[2], r[3], 1, 5, 3, 7);
    c[0] = SHUF(t0, t2, 0, 1, 4, 5); c[1] = SHUF(t1, t3, 0, 1, 4, 5);
    c[2] = SHUF(t0, t2, 2, 3, 6, 7); c[3] = SHUF(t1, t3, 2, 3, 6, 7);
}



/* lane q's coefficients at its local variable sq as rows (coef4): lo (M, dM, Vg, dVg, from
 * its cell r, mass-corrected where dm != 0) and hi (l, dl, dd, tau, from rh: the cell's, or
 * the row's own pieces) */
ALWAYS void lane_rows(const Table *T, const Par4 *P, int q, const double *r, const double *rh,
                      double sq, v4 *lo, v4 *hi)
{
    lo[q] = cubic4(r, NC, sq);
    hi[q] = cubic4(rh + 4, NC, sq);
    if (P->any && P->dm[q] != 0.0) { /* M, dM, Vg, dVg only */
        const double *rm = T->dcc + (r - T->cc);
        lo[q] += P->dm[q] * cubic4(rm, NC, sq);
    }
}

/* coef4's rows of a group with a lane that has its own points: the same operations, with a
 * lane's l, dl, dd, tau read from its row's own pieces (PER-ROW ATTACHMENT POINTS) -- a loop
 * of its own: inside coef4's loop the lookup slowed the lanes without points by 6 % */
ALWAYS void coef4_pts(const Table *T, const Par4 *P, const double *const *b, const v4 *s,
                      v4 *lo, v4 *hi)
{
    for (int q = 0; q < VW; q++) {
        const double *r = b[q], *rh = r;
        if (P->lpts[q]) {
            const PtCache *c = P->lp[q]->pc;
            int i = (int)((r - T->cc) / (4 * NC));
            rh = (unsigned)(i - c->base) < (unsigned)c->nb ? c->blk[i - c->base]
                                                           : pt_build(T, P->lp[q], i);
        }
        lane_rows(T, P, q, r, rh, (*s)[q], lo, hi);
    }
}

/* the NC coefficients of the lanes at th as columns c[j] (four lanes each): each lane's
 * cubic pieces are evaluated as rows (lane_rows: Horner in s, as cubic, mass-corrected where
 * dm != 0), then transposed; okm as cells4's */
ALWAYS void coef4(const Table *T, const Par4 *P, v4 th, v4 *c, const double **b, v4 *s,
                  v4l *okm, const int pts)
{ /* (pts: the group has a lane with its own points -- a literal: see rhs4, node4) */
    v4 lo[VW], hi[VW];
    cells4(T, th, b, s, okm);
    if (pts) {
        coef4_pts(T, P, b, s, lo, hi);
    } else {
        for (int q = 0; q < VW; q++) lane_rows(T, P, q, b[q], b[q], (*s)[q], lo, hi);
    }
    transpose4(lo, c);
    transpose4(hi, c + 4);
}

/* ELEM_ONE_WAY for lanes: 0 where the lane's dampers are one-way and th' > 0 */
ALWAYS v4 one_way4(const Par4 *P, v4 thd, v4 damp)
{
    v4 zero = {0.0, 0.0, 0.0, 0.0};
    return sel4(P->ow & (thd > zero), zero, damp);
}

/* the element columns of the lanes (cells b, local variables s from coef4) as columns x[j] */
ALWAYS void xcoef4(const Table *T, const double *const *b, v4 s, v4 *x)
{
    v4 r[VW];
    for (int q = 0; q < VW; q++) {
        const double *xr = T->xcc + (size_t)((b[q] - T->cc) / NC) * NX;
        double sq = s[q];
        r[q] = cubic4(xr, NX, sq);
    }
    transpose4(r, x);
}

/* theta'' of the lanes (as rhs()); okm as cells4's */
ALWAYS v4 rhs4_impl(const Table *T, const Par4 *P, v4 th, v4 thd, v4l *okm, const int pts)
{
    v4 c[NC], s;
    const double *b[VW];
    coef4(T, P, th, c, b, &s, okm, pts);
    v4 damp = ELEM_DAMPING(P, c), slope = ELEM_SLOPE(P, c);
    if (P->anyx) {
        v4 x[NX];
        xcoef4(T, b, s, x);
        slope += ELEM_SLOPE_X(P, x); damp += ELEM_DAMPING_X(P, x);
    }
    if (P->anye) damp += ELEM_DAMPING_E(P);
    if (P->anyow) damp = one_way4(P, thd, damp);
    v4 N = -slope - 0.5 * c[C_DM] * thd * thd - damp * thd;
    if (P->anyf) N -= ELEM_FRICTION(P, c);
    return N / c[C_M];
}

/* a group with a lane that has its own points runs rhs4 and node4 in functions of their own
 * (PER-ROW ATTACHMENT POINTS): inlined beside the others, its code slowed the groups without
 * points by a few per cent (both compiled for the vector path, the only one that calls them) */
#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define PTS_TARGET __attribute__((target("avx2"), noinline))
#else
#define PTS_TARGET __attribute__((noinline))
#endif
PTS_TARGET static void rhs4_pts(const Table *T, const Par4 *P, const v4 *th, const v4 *thd,
                                v4l *okm, v4 *out)
{
    *out = rhs4_impl(T, P, *th, *thd, okm, 1);
}

ALWAYS v4 rhs4(const Table *T, const Par4 *P, v4 th, v4 thd, v4l *okm)
{
    if (__builtin_expect(P->anyp, 0)) {
        v4 r;
        rhs4_pts(T, P, &th, &thd, okm, &r);
        return r;
    }
    return rhs4_impl(T, P, th, thd, okm, 0);
}

/* node_eval() of the lanes: theta'', tip speed, its rate, energy, potential, as vectors
 * (ok: 1 inside the table, 0 outside) -- the same operations as node_eval() lane by lane */
ALWAYS void node4_impl(const Table *T, const Par4 *P, v4 th, v4 thd, v4 *a, v4 *g, v4 *dg,
                       v4 *Ev, v4 *Vv, v4 *ok, const int pts)
{
    v4 c[NC], s;
    const double *b[VW];
    v4l okm;
    coef4(T, P, th, c, b, &s, &okm, pts);
    v4 M = c[C_M], dM = c[C_DM], tau = c[C_TAU];
    v4 damp = ELEM_DAMPING(P, c), slope = ELEM_SLOPE(P, c);
    v4 En = ELEM_ENERGY(P, c, 0.5 * M * thd * thd), Vn = ELEM_POTENTIAL(P, c);
    if (P->anyx) {
        v4 x[NX];
        xcoef4(T, b, s, x);
        slope += ELEM_SLOPE_X(P, x); damp += ELEM_DAMPING_X(P, x);
        En += ELEM_POTENTIAL_X(P, x); Vn += ELEM_POTENTIAL_X(P, x);
    }
    if (P->anye) damp += ELEM_DAMPING_E(P);
    if (P->anyow) damp = one_way4(P, thd, damp);
    v4 N = -slope - 0.5 * dM * thd * thd - damp * thd;
    if (P->anyf) N -= ELEM_FRICTION(P, c);
    v4 acc = N / M;
    *Ev = En;
    *Vv = Vn;
    /* d tau / d theta (as dcubic) from each lane's cubic of tau */
    v4 q1 = {b[0][NC + C_TAU], b[1][NC + C_TAU], b[2][NC + C_TAU], b[3][NC + C_TAU]};
    v4 q2 = {b[0][2 * NC + C_TAU], b[1][2 * NC + C_TAU], b[2][2 * NC + C_TAU],
             b[3][2 * NC + C_TAU]};
    v4 q3 = {b[0][3 * NC + C_TAU], b[1][3 * NC + C_TAU], b[2][3 * NC + C_TAU],
             b[3][3 * NC + C_TAU]};
    v4 dtau = (q1 + s * (2.0 * q2 + s * 3.0 * q3)) * T->inv_h;
    v4 one = {1.0, 1.0, 1.0, 1.0}, zero = {0.0, 0.0, 0.0, 0.0};
    v4 sg = sel4(thd >= zero, one, -one);
    *a = acc;
    *g = tau * abs4(thd);
    *dg = sg * (dtau * thd * thd + tau * acc);
    *ok = sel4(okm, one, zero);
}

PTS_TARGET static void node4_pts(const Table *T, const Par4 *P, const v4 *th, const v4 *thd,
                                 v4 *a, v4 *g, v4 *dg, v4 *Ev, v4 *Vv, v4 *ok)
{
    node4_impl(T, P, *th, *thd, a, g, dg, Ev, Vv, ok, 1);
}

ALWAYS void node4(const Table *T, const Par4 *P, v4 th, v4 thd, v4 *a, v4 *g, v4 *dg, v4 *Ev,
                  v4 *Vv, v4 *ok)
{
    if (__builtin_expect(P->anyp, 0)) node4_pts(T, P, &th, &thd, a, g, dg, Ev, Vv, ok);
    else node4_impl(T, P, th, thd, a, g, dg, Ev, Vv, ok, 0);
}

/* theta'' only, from the six coefficients it needs (the scalar hot path) */
ALWAYS int rhs_fast(const Table *T, const Par *p, double th, double thd, double *thdd)
{
    double s;
    int i = cell_index(T, th, &s);
    if (i < 0) return 1;
    const double *q = T->cc + (size_t)i * 4 * NC;
    double M = cubic(q + C_M, NC, s), dM = cubic(q + C_DM, NC, s), dVg = cubic(q + C_DVG, NC, s),
           l = cubic(q + C_L, NC, s), dl = cubic(q + C_DL, NC, s), dd = cubic(q + C_DD, NC, s);
    if (p->dm != 0.0) {
        const double *r = T->dcc + (size_t)i * 4 * NC;
        M += p->dm * cubic(r + C_M, NC, s); dM += p->dm * cubic(r + C_DM, NC, s);
        dVg += p->dm * cubic(r + C_DVG, NC, s);
    }
    double c[NC];
    c[C_DVG] = dVg; c[C_L] = l; c[C_DL] = dl; c[C_DD] = dd;
    if (p->ps | p->pd) pts_eval(T, p, i, s, c, NULL);
    double damp = ELEM_DAMPING(p, c), slope = ELEM_SLOPE(p, c);
    if (p->x) {
        double x[NX];
        xtab_eval(T, i, s, x, NULL);
        slope += ELEM_SLOPE_X(p, x); damp += ELEM_DAMPING_X(p, x);
    }
    if (p->e) damp += ELEM_DAMPING_E(p);
    damp = ELEM_ONE_WAY(p, thd, damp);
    double N = -slope - 0.5 * dM * thd * thd - damp * thd;
    if (ELEM_STICKS(p)) N -= ELEM_FRICTION(p, c);
    *thdd = N / M;
    return 0;
}

/* one explicit RK step of the active lanes, lane by lane (for a CPU without wide vectors) */
ALWAYS void explicit_scalar(const Table *T, const Method *m, const int s, Lane *lanes,
                            const int *act, int na, const double *hh, double *y0, double *y1,
                            int *st)
{ /* (outputs indexed by the lane's slot act[q]) */
    double K0[LANES][SMAX], K1[LANES][SMAX];
    for (int q = 0; q < na; q++) {
        Lane *L = &lanes[act[q]];
        K0[q][0] = L->thd; K1[q][0] = L->a; st[act[q]] = 0;
    }
    for (int i = 1; i < s; i++) {
        for (int q = 0; q < na; q++) {
            Lane *L = &lanes[act[q]];
            double h = hh[act[q]], z0 = L->th, z1 = L->thd;
            for (int j = 0; j < i; j++) {
                if (m->A[i][j] != 0.0) {
                    double ha = h * m->A[i][j];
                    z0 += ha * K0[q][j]; z1 += ha * K1[q][j];
                }
            }
            K0[q][i] = z1;
            if (rhs_fast(T, &L->p, z0, z1, &K1[q][i])) { K1[q][i] = NAN; st[act[q]] = S_RANGE; }
        }
    }
    for (int q = 0; q < na; q++) {
        Lane *L = &lanes[act[q]];
        double h = hh[act[q]], z0 = L->th, z1 = L->thd;
        for (int i = 0; i < s; i++) { z0 += h * m->b[i] * K0[q][i]; z1 += h * m->b[i] * K1[q][i]; }
        y0[act[q]] = z0; y1[act[q]] = z1;
    }
}

/* The hot state of the lane slots as arrays (structure of arrays): the vector path keeps it
 * here between steps, so a step's inputs are vector loads and the common case of the
 * bookkeeping after a step is a few vector compares and blends (after_steps_vec). A lane that
 * needs the scalar code (an event, a turning point, a peak to refine, an early-exit check,
 * a failure) is copied into its Lane (soa_in), handled there, and copied back (soa_out). */
typedef struct {
    double th[LANES], thd[LANES], a[LANES], t[LANES], n[LANES], peak[LANES], th_min[LANES],
        th_max[LANES], Vlo[LANES], Vhi[LANES], thd_max[LANES], Emax[LANES], gain[LANES],
        gp[LANES], g[LANES], dg[LANES], E[LANES], thp[LANES], thdp[LANES], hp[LANES],
        E0[LANES], e_tol[LANES], early[LANES], floor_[LANES], wait[LANES];
} Soa;

/* the new nodes of the lane slots (node4 per group): ok 1 inside the table, 0 outside,
 * -1 where the step crossed theta_closed (the event is the scalar code's) */
typedef struct { double a[LANES], g[LANES], dg[LANES], E[LANES], V[LANES], ok[LANES]; } Nodes;

ALWAYS void soa_in(const Soa *S, Lane *L, int k)
{
    L->th = S->th[k]; L->thd = S->thd[k]; L->a = S->a[k]; L->t = S->t[k]; L->n = (long)S->n[k];
    L->peak = S->peak[k]; L->th_min = S->th_min[k]; L->th_max = S->th_max[k];
    L->Vlo = S->Vlo[k]; L->Vhi = S->Vhi[k]; L->thd_max = S->thd_max[k]; L->Emax = S->Emax[k];
    L->gain = S->gain[k]; L->gp = S->gp[k]; L->g = S->g[k]; L->dg = S->dg[k]; L->E = S->E[k];
    L->thp = S->thp[k]; L->thdp = S->thdp[k]; L->hp = S->hp[k]; L->wait = (int)S->wait[k];
}

ALWAYS void soa_out(Soa *S, const Lane *L, int k)
{
    S->th[k] = L->th; S->thd[k] = L->thd; S->a[k] = L->a; S->t[k] = L->t; S->n[k] = (double)L->n;
    S->peak[k] = L->peak; S->th_min[k] = L->th_min; S->th_max[k] = L->th_max;
    S->Vlo[k] = L->Vlo; S->Vhi[k] = L->Vhi; S->thd_max[k] = L->thd_max; S->Emax[k] = L->Emax;
    S->gain[k] = L->gain; S->gp[k] = L->gp; S->g[k] = L->g; S->dg[k] = L->dg; S->E[k] = L->E;
    S->thp[k] = L->thp; S->thdp[k] = L->thdp; S->hp[k] = L->hp;
    S->E0[k] = L->E0; S->e_tol[k] = L->e_tol; S->early[k] = L->early ? 1.0 : 0.0;
    S->floor_[k] = L->floor_; S->wait[k] = (double)L->wait;
}

ALWAYS void st4(double *a, v4 v) { memcpy(a, &v, sizeof v); }

/* one explicit RK step of every lane slot, as NG vectors of VW lanes (slot g VW + q is
 * element q of vector g; idle slots compute from whatever state they hold, look-ups
 * outside the table are caught, and their results are discarded), then the new nodes;
 * the groups are independent, so their dependent chains overlap; s is a literal at the
 * hot call. P: the lanes' parameters as vectors (kept up to date by lane_start). */
ALWAYS void explicit_lanes(const Table *T, const Method *m, const int s, const Soa *S,
                           const Par4 *P, const double *hh, double *y0, double *y1, int *st,
                           Nodes *nd, double thc)
{
    v4 th[NG], thd[NG], h[NG], K0[NG][SMAX], K1[NG][SMAX];
    for (int g = 0; g < NG; g++) {
        th[g] = ld4(S->th + g * VW); thd[g] = ld4(S->thd + g * VW); h[g] = ld4(hh + g * VW);
        K1[g][0] = ld4(S->a + g * VW);
        for (int q = 0; q < VW; q++) st[g * VW + q] = 0;
    }
    for (int g = 0; g < NG; g++) K0[g][0] = thd[g];
    for (int i = 1; i < s; i++) {
        v4l okm[NG];
        for (int g = 0; g < NG; g++) {
            v4 z0 = th[g], z1 = thd[g];
            for (int j = 0; j < i; j++) {
                if (m->A[i][j] != 0.0) {
                    v4 ha = h[g] * m->A[i][j];
                    z0 += ha * K0[g][j]; z1 += ha * K1[g][j];
                }
            }
            K0[g][i] = z1;
            K1[g][i] = rhs4(T, P + g, z0, z1, &okm[g]);
        }
        for (int g = 0; g < NG; g++) {
            v4l bad = ~okm[g];
            if (bad[0] | bad[1] | bad[2] | bad[3])
                for (int q = 0; q < VW; q++)
                    if (bad[q]) { K1[g][i][q] = NAN; st[g * VW + q] = S_RANGE; }
        }
    }
    for (int g = 0; g < NG; g++) {
        v4 z0 = th[g], z1 = thd[g];
        for (int i = 0; i < s; i++) {
            z0 += h[g] * m->b[i] * K0[g][i]; z1 += h[g] * m->b[i] * K1[g][i];
        }
        /* the new nodes (a lane that closed, failed or left the table ignores its node) */
        const int b = g * VW;
        st4(y0 + b, z0); st4(y1 + b, z1);
        v4l ev = ~(z0 > (v4){thc, thc, thc, thc});
        v4 zs = sel4(ev, th[g], z0); /* keep the look-up inside the table */
        v4 a, gg, dg, E, V, ok;
        node4(T, P + g, zs, z1, &a, &gg, &dg, &E, &V, &ok);
        st4(nd->a + b, a); st4(nd->g + b, gg); st4(nd->dg + b, dg); st4(nd->E + b, E);
        st4(nd->V + b, V);
        st4(nd->ok + b, sel4(ev, ok * 0.0 - 1.0, ok)); /* lane_after_step sees the event */
    }
}

/* lane_after_step() for the active slots of the vector path. A lane whose step takes none
 * of that function's special branches (closing event, failure, a peak to refine, a turning
 * point, an unstable energy rise) gets the same updates as vector blends, in the same
 * order and with the same operations, so its state is the scalar code's bit for bit; a lane
 * whose early-exit trigger fires then goes through lane_try_exit as it would there. Every
 * other lane (and every lane of a trajectory run: `scalar`) runs lane_after_step itself. */
ALWAYS void after_steps_vec(const Table *T, const Method *m, Lane *lanes, Soa *S, Par4 *P,
                            int *used,
                            const double *hh, const double *y0, const double *y1,
                            const int *st, const Nodes *nd, double thc, double dt,
                            double t_max, long *traj_len, int scalar)
{
    const double inv_dt = 1.0 / dt; /* (as lane_start's) */
    const v4 zero = {0.0, 0.0, 0.0, 0.0}, one = {1.0, 1.0, 1.0, 1.0};
    const v4 inf = {INFINITY, INFINITY, INFINITY, INFINITY}, c4 = zero + thc;
    for (int g = 0; g < NG; g++) {
        const int b = g * VW;
        v4l f = {0, 0, 0, 0}, trig = {0, 0, 0, 0};
        v4 th = ld4(S->th + b), thd = ld4(S->thd + b);
        if (!scalar) {
            v4 h = ld4(hh + b), z0 = ld4(y0 + b), z1 = ld4(y1 + b);
            v4 a1 = ld4(nd->a + b), g1 = ld4(nd->g + b), dg1 = ld4(nd->dg + b);
            v4 E1 = ld4(nd->E + b), V1 = ld4(nd->V + b);
            v4l ok = (v4l){-(long long)(used[b] && !st[b]), -(long long)(used[b + 1] && !st[b + 1]),
                           -(long long)(used[b + 2] && !st[b + 2]),
                           -(long long)(used[b + 3] && !st[b + 3])}
                     & (ld4(nd->ok + b) == one);
            v4 n = ld4(S->n + b), gg = ld4(S->g + b), gp = ld4(S->gp + b), E = ld4(S->E + b);
            v4l refine = ((n + one) > one) & (gg >= gp) & (gg > g1);
            v4l turn = ((thd < zero) & (z1 >= zero)) | ((thd > zero) & (z1 <= zero));
            if (P[g].anyf) turn |= z1 * P[g].fs < zero; /* a rest (also right after one) */
            /* a crossing of the end damper's engagement angle (ELEM_CROSSED): an event */
            if (P[g].anye) turn |= (z0 < P[g].the) ^ P[g].egm;
            f = ok & (abs4(z0) < inf) & (abs4(z1) < inf) & (z0 > c4) & ~refine & ~turn
                & (abs4(E1) < inf) & ~((E1 - ld4(S->E0 + b)) > ld4(S->e_tol + b));
            v4 peak = ld4(S->peak + b), thmin = ld4(S->th_min + b), thmax = ld4(S->th_max + b);
            v4 Vlo = ld4(S->Vlo + b), Vhi = ld4(S->Vhi + b), thdmax = ld4(S->thd_max + b);
            v4 Emax = ld4(S->Emax + b), gain = ld4(S->gain + b), dE = E1 - E;
            v4l lo = f & (z0 < thmin), hi = f & (z0 > thmax);
            st4(S->peak + b, sel4(f & (g1 > peak), g1, peak));
            thmin = sel4(lo, z0, thmin); Vlo = sel4(lo, V1, Vlo);
            thmax = sel4(hi, z0, thmax); Vhi = sel4(hi, V1, Vhi);
            st4(S->th_min + b, thmin); st4(S->Vlo + b, Vlo);
            st4(S->th_max + b, thmax); st4(S->Vhi + b, Vhi);
            st4(S->thd_max + b, sel4(f & (z1 > thdmax), z1, thdmax));
            st4(S->Emax + b, sel4(f & (E1 > Emax), E1, Emax));
            st4(S->gain + b, sel4(f & (dE > gain), dE, gain));
            st4(S->gp + b, sel4(f, gg, gp));
            st4(S->thp + b, sel4(f, th, ld4(S->thp + b)));
            st4(S->thdp + b, sel4(f, thd, ld4(S->thdp + b)));
            st4(S->hp + b, sel4(f, h, ld4(S->hp + b)));
            st4(S->g + b, sel4(f, g1, gg));
            st4(S->dg + b, sel4(f, dg1, ld4(S->dg + b)));
            st4(S->a + b, sel4(f, a1, ld4(S->a + b)));
            st4(S->E + b, sel4(f, E1, E));
            v4 t = ld4(S->t + b);
            st4(S->t + b, sel4(f, t + h, t));
            st4(S->n + b, sel4(f, n + one, n));
            st4(S->th + b, sel4(f, z0, th));
            st4(S->thd + b, sel4(f, z1, thd));
            v4l fixed = (z0 == th) & (z1 == thd);
            trig = f & (ld4(S->early + b) != zero) & (fixed | ((E1 < Vlo) & (E1 < Vhi)));
            /* lane_try_exit's first test, as it would make it: a lane whose energy with its
             * margin still reaches a visited end returns at once, nothing changed */
            v4 left = ((v4){t_max, t_max, t_max, t_max} - (t + h)) * inv_dt + 1.0;
            v4 Eh = E1 + 2.0 * left * ld4(S->gain + b) + ld4(S->floor_ + b);
            trig &= fixed | ((Eh < Vlo) & (Eh < Vhi));
            /* and its second: a lane still waiting after a failed speed bound counts down */
            v4 wait = ld4(S->wait + b);
            v4l down = trig & ~fixed & (wait > zero);
            st4(S->wait + b, sel4(down, wait - one, wait));
            trig &= ~down;
            v4l need = ~f | trig;
            if (!(need[0] | need[1] | need[2] | need[3])) continue; /* all four: common case */
        }
        for (int q = 0; q < VW; q++) {
            const int k = b + q;
            if (!used[k] || (f[q] && !trig[q])) continue;
            Lane *L = &lanes[k];
            soa_in(S, L, k);
            Node node = {nd->a[k], nd->g[k], nd->dg[k], nd->E[k], nd->V[k], (int)nd->ok[k]};
            int over = f[q] ? lane_try_exit(T, L, thc, th[q], thd[q])
                            : lane_after_step(T, m, L, hh[k], y0[k], y1[k], st[k], thc, &node);
            if (over) {
                lane_finish(T, L, thc, t_max);
                if (traj_len) *traj_len = L->nt;
                used[k] = 0;
            } else {
                soa_out(S, L, k);
                P[g].fs[q] = L->p.fs;     /* a rest of dry friction sets the direction */
                ELEM_LANE_ENGAGE(&P[g], q, &L->p); /* a crossing of theta_e, the state */
            }
        }
    }
}

/* n strokes (rows of design, ncol columns: NDESIGN - 1, the element parameters (D_*) and
 * e_tol; NDESIGN, then m_lid; or NDESIGN + NPT, then the row's own points) into out
 * (n x NOUT); early: stop a stroke as soon as nothing can change (see the top); with
 * traj (n must be 1) the rows (t, th, thd) of every node */
ALWAYS void strokes(const Table *T, const Method *m, double dt, double t_max, double th0,
                   double thc, long n, int ncol, const double *design, int early, double *out,
                   double *traj, long traj_cap, long *traj_len, const int vec)
{
    Lane lanes[LANES];
    PtCache pcache[LANES];
    Par4 P[NG];
    int used[LANES] = {0};
    long next = 0;
    int nlanes = traj ? 1 : LANES;
    const int s = m->s;
    double hh[LANES] = {0};
    Soa S; /* the hot lane state of the vector path (see Soa) */
    const int fv = vec && m->kind == 0;
    memset(lanes, 0, sizeof lanes);
    memset(P, 0, sizeof P);
    memset(&S, 0, sizeof S);
    for (;;) {
        int act[LANES], na = 0;
        if (fv && nlanes == LANES) { /* the common case: every slot busy, none at t_max */
            const v4 dtv = {dt, dt, dt, dt}, tmv = {t_max, t_max, t_max, t_max};
            const double eps = 1e-15 * t_max;
            int all = 1;
            for (int k = 0; k < LANES; k++) all &= used[k] != 0;
            for (int g = 0; all && g < NG; g++) {
                v4 t = ld4(S.t + g * VW), h = sel4(dtv < tmv - t, dtv, tmv - t);
                v4l okv = (t < tmv) & (h > (v4){eps, eps, eps, eps});
                st4(hh + g * VW, h);
                for (int q = 0; q < VW; q++) all &= okv[q] != 0;
            }
            if (all) na = LANES; /* (act is not used by the vector path) */
        }
        for (int k = 0; na < LANES && k < nlanes; k++) {
            for (;;) {
                if (used[k]) {
                    Lane *L = &lanes[k];
                    double tk = fv ? S.t[k] : L->t;
                    double h = dt < t_max - tk ? dt : t_max - tk;
                    if (tk < t_max && h > 1e-15 * t_max) { hh[k] = h; break; }
                    if (fv) soa_in(&S, L, k);
                    lane_finish(T, L, thc, t_max); /* ran to t_max without closing */
                    if (traj_len) *traj_len = L->nt;
                    used[k] = 0;
                }
                hh[k] = 0.0;
                if (next >= n) break;
                used[k] = 1;
                Lane *L = &lanes[k];
                L->p.pc = &pcache[k]; /* (its own pieces, with points: emptied by lane_start) */
                int over = lane_start(T, L, design + (size_t)ncol * next, ncol,
                                      out + NOUT * next, th0, thc, dt, t_max, early, traj,
                                      traj_cap);
                Par4 *G = &P[k / VW];
                int q = k % VW;
                ELEM_LANE(G, q, &L->p);
                G->dm[q] = L->p.dm;
                G->lp[q] = &L->p;
                G->any = 0; G->anyx = 0; G->anyow = 0; G->anyf = 0; G->anye = 0; G->anyp = 0;
                G->anyg = 0;
                for (int e = 0; e < VW; e++) {
                    G->lp[e] = &lanes[k - q + e].p;
                    G->lpts[e] = lanes[k - q + e].p.ps | lanes[k - q + e].p.pd;
                    G->anyp |= (lanes[k - q + e].p.ps | lanes[k - q + e].p.pd) && used[k - q + e];
                    G->any |= G->dm[e] != 0.0;
                    G->anyx |= lanes[k - q + e].p.x && used[k - q + e];
                    G->anyow |= lanes[k - q + e].p.ow && used[k - q + e];
                    G->anyf |= ELEM_STICKS(&lanes[k - q + e].p) && used[k - q + e];
                    G->anye |= lanes[k - q + e].p.e && used[k - q + e];
                    G->anyg |= lanes[k - q + e].p.anyg && used[k - q + e];
                }
                if (over) {
                    lane_finish(T, L, thc, t_max);
                    if (traj_len) *traj_len = L->nt;
                    used[k] = 0;
                } else if (fv) {
                    soa_out(&S, L, k);
                }
                next++;
            }
            if (used[k]) act[na++] = k;
        }
        if (na == 0) break;
        /* the step of every active lane; results by slot */
        double y0[LANES], y1[LANES];
        int st[LANES];
        if (fv) { /* explicit RK, lanes as vectors, first stage: the node */
            Nodes nd;
            if (s == 4) explicit_lanes(T, m, 4, &S, P, hh, y0, y1, st, &nd, thc);
            else explicit_lanes(T, m, s, &S, P, hh, y0, y1, st, &nd, thc);
            after_steps_vec(T, m, lanes, &S, P, used, hh, y0, y1, st, &nd, thc, dt, t_max,
                            traj_len, traj != NULL);
            continue;
        }
        if (m->kind == 0) { /* explicit RK, lane by lane */
            if (s == 4) explicit_scalar(T, m, 4, lanes, act, na, hh, y0, y1, st);
            else explicit_scalar(T, m, s, lanes, act, na, hh, y0, y1, st);
        } else if (m->kind == 2) { /* symplectic Euler from the node's theta'' */
            for (int q = 0; q < na; q++) {
                int k = act[q];
                Lane *L = &lanes[k];
                y1[k] = L->thd + hh[k] * L->a;
                y0[k] = L->th + hh[k] * y1[k];
                st[k] = 0;
            }
        } else {
            for (int q = 0; q < na; q++) {
                int k = act[q];
                Lane *L = &lanes[k];
                st[k] = step(T, m, &L->p, hh[k], L->th, L->thd, &y0[k], &y1[k]);
            }
        }
        for (int q = 0; q < na; q++) {
            int k = act[q];
            if (lane_after_step(T, m, &lanes[k], hh[k], y0[k], y1[k], st[k], thc, NULL)) {
                lane_finish(T, &lanes[k], thc, t_max);
                if (traj_len) *traj_len = lanes[k].nt;
                used[k] = 0;
            }
        }
    }
}

/* the stroke loop compiled twice: with AVX2 (lanes as 4-wide vectors; no FMA, so every
 * operation is the scalar one and the results are the same bit for bit) and for any CPU */
#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define SC_AVX2 1
__attribute__((target("avx2"), noinline))
static void strokes_avx2(const Table *T, const Method *m, double dt, double t_max, double th0,
                         double thc, long n, int ncol, const double *design, int early,
                         double *out, double *traj, long traj_cap, long *traj_len)
{
    strokes(T, m, dt, t_max, th0, thc, n, ncol, design, early, out, traj, traj_cap, traj_len, 1);
}
#endif

__attribute__((noinline))
static void strokes_any(const Table *T, const Method *m, double dt, double t_max, double th0,
                        double thc, long n, int ncol, const double *design, int early,
                        double *out, double *traj, long traj_cap, long *traj_len)
{
    strokes(T, m, dt, t_max, th0, thc, n, ncol, design, early, out, traj, traj_cap, traj_len, 0);
}

static int use_vec = -1; /* -1: not decided; SC_SCALAR=1 in the environment forces 0 */
/* (pt_build reads it: decided before any stroke, and run() is the only way to a stroke) */

static void run(const Table *T, const Method *m, double dt, double t_max, double th0,
                double thc, long n, int ncol, const double *design, int early, double *out,
                double *traj, long traj_cap, long *traj_len)
{
#ifdef SC_AVX2
    if (use_vec < 0) {
        const char *e = getenv("SC_SCALAR");
        __builtin_cpu_init();
        use_vec = __builtin_cpu_supports("avx2") && !(e && *e == '1');
    }
    if (use_vec) {
        strokes_avx2(T, m, dt, t_max, th0, thc, n, ncol, design, early, out, traj, traj_cap,
                     traj_len);
        return;
    }
#endif
    strokes_any(T, m, dt, t_max, th0, thc, n, ncol, design, early, out, traj, traj_cap, traj_len);
}

/* ---- exported entry points (called through ctypes; the GIL is released) ----
 * tab_meta = (ncell, lo, h, m0, rotary_at_pivot); cc: ncell x 4 x NC; dcc: the same, or NULL; rng: ncell x
 * NRNG (see the Table) or NULL */

static void make(const double *tab_meta, const double *cc, const double *dcc,
                 const double *xcc, const double *rng, const double *pcc,
                 const double *tableau, Table *T, Method *m)
{
    T->crit = NULL; T->ncrit = 0;
    T->cc = cc; T->dcc = dcc; T->xcc = xcc; T->rng = rng; T->pcc = pcc;
    T->ncell = (int)tab_meta[0]; T->lo = tab_meta[1];
    T->h = tab_meta[2]; T->m0 = tab_meta[3]; T->rot_pivot = tab_meta[4] != 0.0;
    T->inv_h = 1.0 / T->h;
    T->pA1 = T->pA2 = 0.0;
    if (pcc) pts_bounds(T);
    m->kind = (int)tableau[0]; m->s = (int)tableau[1];
    int s = m->s;
    for (int i = 0; i < s; i++) {
        for (int j = 0; j < s; j++) m->A[i][j] = tableau[2 + i * s + j];
        m->b[i] = tableau[2 + s * s + i];
        m->c[i] = tableau[2 + s * s + s + i];
    }
}

/* strokes for n designs (rows of `design`, ncol columns: the element parameters, e_tol[,
 * m_lid[, the NPT point columns]], as strokes()); out: n x NOUT */
/* the list of cells where l' may vanish (T->crit), from the cell ranges; NULL (all cells
 * are searched) without them or if memory is short. The caller frees it. */
static int *critical_cells(Table *T)
{
    if (!T->rng) return NULL;
    int *crit = malloc(sizeof(int) * (size_t)(T->ncell > 0 ? T->ncell : 1));
    if (!crit) return NULL;
    int nc = 0;
    for (int i = 0; i < T->ncell; i++)
        if (T->rng[(size_t)i * NRNG + R_LCRIT] != 0.0) crit[nc++] = i;
    T->crit = crit; T->ncrit = nc;
    return crit;
}

void sc_strokes(const double *tab_meta, const double *cc, const double *dcc,
                const double *xcc, const double *rng, const double *pcc, const double *tableau,
                double dt, double t_max, double th0, double thc, long n, long ncol,
                const double *design, long early, double *out)
{
    Table T; Method m;
    make(tab_meta, cc, dcc, xcc, rng, pcc, tableau, &T, &m);
    int *crit = critical_cells(&T);
    run(&T, &m, dt, t_max, th0, thc, n, (int)ncol, design, (int)early, out, NULL, 0, NULL);
    free(crit);
}

/* one stroke with its trajectory */
void sc_stroke_traj(const double *tab_meta, const double *cc, const double *dcc,
                    const double *xcc, const double *rng, const double *pcc,
                    const double *tableau, double dt, double t_max, double th0, double thc,
                    long ncol, const double *design, long early, double *out, double *traj,
                    long traj_cap, long *traj_len)
{
    Table T; Method m;
    make(tab_meta, cc, dcc, xcc, rng, pcc, tableau, &T, &m);
    int *crit = critical_cells(&T);
    *traj_len = 0;
    run(&T, &m, dt, t_max, th0, thc, 1, (int)ncol, design, (int)early, out, traj, traj_cap,
        traj_len);
    free(crit);
}

/* one step (for tests): x1 = step(x0, h); design: a full row (LAYOUT, with m_lid and the
 * point columns); the end damper engaged as at x0 (theta < theta_e), for the whole step */
int sc_step(const double *tab_meta, const double *cc, const double *dcc, const double *xcc,
            const double *pcc, const double *tableau, const double *design, double h,
            const double *x0, double *x1)
{
    Table T; Method m;
    make(tab_meta, cc, dcc, xcc, NULL, pcc, tableau, &T, &m);
    Par p;
    PtCache pc;
    ELEM_READ(&p, design, &T);
    ELEM_ENGAGE_START(&p, x0[0], -INFINITY);
    p.pc = &pc;
    pts_read(&p, design, D_PT + NPT);
    p.dm = 0.0;
    if (p.x && !xcc) return S_RANGE;
    if ((p.ps | p.pd) && !pcc) return S_RANGE;
    if (isfinite(design[D_LID_MASS]) && design[D_LID_MASS] != T.m0) {
        if (!dcc) return S_RANGE;
        p.dm = design[D_LID_MASS] - T.m0;
    }
    return step(&T, &m, &p, h, x0[0], x0[1], &x1[0], &x1[1]);
}

/* the spring's l, dl and the dashpot's dd of rows with their own points (pts: n x NPT, the
 * row convention) at angles th (n x G, or G shared by the rows), from the rows' pieces as the
 * strokes read them: out n x G x 3 (NaN where the row has the table's, or outside it) */
void sc_point_columns(const double *tab_meta, const double *cc, const double *pcc, long n,
                      const double *pts, long G, const double *th, long shared, double *out)
{
    static const double tableau[5] = {0, 1, 0, 1, 0};
    Table T; Method m;
    make(tab_meta, cc, NULL, NULL, NULL, pcc, tableau, &T, &m);
    for (long r = 0; r < n; r++) {
        Par p;
        PtCache pc;
        memset(&p, 0, sizeof p);
        p.pc = &pc;
        pts_set(&p, pts + (size_t)r * NPT);
        for (long g = 0; g < G; g++) {
            double x = shared ? th[g] : th[(size_t)r * G + g], s, v[NC];
            double *o = out + ((size_t)r * G + g) * 3;
            o[0] = o[1] = o[2] = NAN;
            int i = cell_index(&T, x, &s);
            if (i < 0) continue;
            pts_eval(&T, &p, i, s, v, NULL);
            if (p.ps) { o[0] = v[C_L]; o[1] = v[C_DL]; }
            if (p.pd) o[2] = v[C_DD];
        }
    }
}

/* the same columns for many rows over a grid of angles shared by the rows, from the pose
 * pieces interpolated at the angles (not the rows' pieces: within the tables' interpolation
 * error, ~1e-10 relative, of them; for the statics that scan a stroke: the opening effort,
 * where a spring leaves its range): pose_g (G x P_USED) the pose at the grid, out n x G x 3 */
#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define PG_SQRT(x) __builtin_ia32_sqrtpd256(x)
__attribute__((target("avx2")))
#else
#define PG_SQRT(x) ({ v4 y_ = (x); for (int q_ = 0; q_ < VW; q_++) y_[q_] = sqrt(y_[q_]); y_; })
#endif
static void point_grid_rows(const double *pose_g, long G4, long G, long n, const double *pts,
                            int mode, const double *ab, double *out)
{ /* (four angles at a time: the pose padded to G4, a multiple of 4; G angles written; mode
   * 0: l, dl, dd an angle; 1: l; 2: the spring's slope term (a + b l) l', ab: a, b a row) */
    const double *Ax = pose_g, *Ay = pose_g + G4, *dAx = pose_g + 2 * G4,
                 *dAy = pose_g + 3 * G4, *cs = pose_g + 4 * G4, *sn = pose_g + 5 * G4;
    for (long r = 0; r < n; r++) {
        const double *g = pts + (size_t)r * NPT;
        double *o = out + (size_t)r * G * (mode ? 1 : 3);
        int ps = isfinite(g[0]) && isfinite(g[1]) && isfinite(g[2]) && isfinite(g[3]);
        int pd = isfinite(g[4]) && isfinite(g[5]) && isfinite(g[6]) && isfinite(g[7]);
        for (long k = 0; k < G4; k += VW) {
            v4 c = ld4(cs + k), sv = ld4(sn + k), ax = ld4(Ax + k), ay = ld4(Ay + k);
            v4 dx = ld4(dAx + k), dy = ld4(dAy + k), l = {NAN, NAN, NAN, NAN}, dl = l, dd = l;
            if (ps) {
                v4 qx = c * g[2] - sv * g[3], qy = sv * g[2] + c * g[3];
                v4 rx = ax + qx - g[0], ry = ay + qy - g[1], ux = dx - qy, uy = dy + qx;
                l = PG_SQRT(rx * rx + ry * ry);
                dl = (rx * ux + ry * uy) / l;
            }
            if (pd) {
                v4 qx = c * g[6] - sv * g[7], qy = sv * g[6] + c * g[7];
                v4 rx = ax + qx - g[4], ry = ay + qy - g[5], ux = dx - qy, uy = dy + qx;
                v4 w = rx * ux + ry * uy;
                dd = w * w / (rx * rx + ry * ry);
            }
            if (mode == 0)
                for (int q = 0; q < VW && k + q < G; q++) {
                    o[3 * (k + q)] = l[q]; o[3 * (k + q) + 1] = dl[q];
                    o[3 * (k + q) + 2] = dd[q];
                }
            else {
                v4 x = mode == 1 ? l : (ab[2 * r] + ab[2 * r + 1] * l) * dl;
                for (int q = 0; q < VW && k + q < G; q++) o[k + q] = x[q];
            }
        }
    }
}

/* the pose (P_USED columns, G4 apart) at the G angles th, from the pose pieces pcc of the
 * table tab_meta, into pose_g; the padding to whole vectors (G..G4) a harmless cos = 1 */
static void pose_at_angles(const double *tab_meta, const double *pcc, const double *th, long G,
                           long G4, double *pose_g)
{
    int ncell = (int)tab_meta[0];
    double lo = tab_meta[1], h = tab_meta[2];
    for (long k = 0; k < G; k++) {
        double x = (th[k] - lo) / h;
        if (x < 0) x = 0;
        if (x > ncell) x = ncell;
        int i = (int)x;
        if (i >= ncell) i = ncell - 1;
        double s = x - i;
        const double *q = pcc + (size_t)i * 4 * NPOSE;
        for (int j = 0; j < P_USED; j++) pose_g[j * G4 + k] = cubic(q + j, NPOSE, s);
    }
    for (long k = G; k < G4; k++) pose_g[P_COS * G4 + k] = 1.0;
}

void sc_point_grid(const double *tab_meta, const double *pcc, long n, const double *pts,
                   long G, const double *th, long per_row, long mode, const double *ab,
                   double *out)
{ /* (th: G angles shared by the rows, or n x G with per_row; mode, ab: point_grid_rows) */
    long G4 = (G + VW - 1) / VW * VW; /* (padded to whole vectors) */
    double *pose_g = calloc((size_t)(G4 > 0 ? G4 : 1) * P_USED, sizeof(double));
    if (!pose_g) {
        for (size_t k = 0; k < (size_t)n * G * (mode ? 1 : 3); k++) out[k] = NAN;
        return;
    }
    for (long r = 0; r < (per_row ? n : 1); r++) {
        /* (a row on the previous row's angles -- rows over the same stroke -- keeps its pose) */
        int same = r > 0 && !memcmp(th + (size_t)r * G, th + (size_t)(r - 1) * G,
                                    sizeof(double) * (size_t)G);
        if (!same) pose_at_angles(tab_meta, pcc, th + (size_t)r * G * (per_row != 0), G, G4,
                                  pose_g);
        if (per_row)
            point_grid_rows(pose_g, G4, G, 1, pts + (size_t)r * NPT, (int)mode,
                            ab ? ab + 2 * r : NULL, out + (size_t)r * G * (mode ? 1 : 3));
    }
    if (!per_row) point_grid_rows(pose_g, G4, G, n, pts, (int)mode, ab, out);
    free(pose_g);
}

/* the opening effort of rows with their own spring points (pts n x NPT, ab their affine law
 * T = a + b l): per row, the largest (base[idx] + (a + b l) l') / tau over the grid th (G
 * angles; base u x G: the other elements' slope and friction of the row's parameters, tau
 * the tip's lever there), refined by the parabola through it and its neighbours -- as
 * softclose.statics.opening_forces does for the table's spring */
void sc_point_opening(const double *tab_meta, const double *pcc, long n, const double *pts,
                      const double *ab, long G, const double *th, const double *base,
                      const long *idx, const double *tau, double *out)
{
    double *buf = malloc(sizeof(double) * (size_t)(G > 0 ? G : 1));
    if (!buf) { for (long r = 0; r < n; r++) out[r] = NAN; return; }
    long G4 = (G + VW - 1) / VW * VW;
    double *pose_g = calloc((size_t)(G4 > 0 ? G4 : 1) * P_USED, sizeof(double));
    if (!pose_g) { free(buf); for (long r = 0; r < n; r++) out[r] = NAN; return; }
    pose_at_angles(tab_meta, pcc, th, G, G4, pose_g);
    for (long r = 0; r < n; r++) {
        point_grid_rows(pose_g, G4, G, 1, pts + (size_t)r * NPT, 2, ab + 2 * r, buf);
        const double *bs = base + (size_t)idx[r] * G;
        long j = 0;
        double best = -INFINITY;
        for (long k = 0; k < G; k++) {
            buf[k] = (bs[k] + buf[k]) / tau[k];
            if (k == 0 || buf[k] > best) { best = buf[k]; j = k; } /* (the first largest) */
        }
        if (j > 0 && j < G - 1) {
            double y0 = buf[j - 1], y1 = buf[j], y2 = buf[j + 1], den = y0 - 2 * y1 + y2;
            double peak = den < 0 ? y1 - (y2 - y0) * (y2 - y0) / (8 * den) : y1;
            if (peak > best) best = peak;
        }
        out[r] = best;
    }
    free(pose_g);
    free(buf);
}

/* where each row's coordinate q (m x G, on its angles th, m x G) leaves its valid range
 * beyond bound (short: below it, else above): the edge of the region beyond it nearest its
 * worst point (interpolated between two angles; NaN when beyond on the whole grid) and the
 * worst point (refined by the parabola through it and its neighbours) -- the arithmetic of
 * softclose.statics._leaves, row by row (b = how far beyond; the first largest b is the
 * worst, a NaN b counting as the largest, as numpy's argmax does) */
void sc_leaves(long m, long G, const double *th, const double *q, const double *bound,
               const double *shrt, double *edge, double *worst)
{
    for (long r = 0; r < m; r++) {
        const double *t = th + (size_t)r * G, *qr = q + (size_t)r * G;
        double bd = bound[r], best = 0.0;
        int sh = shrt[r] != 0.0;
        long w = 0;
#define LV_B(j) (sh ? bd - qr[j] : qr[j] - bd)
        for (long j = 0; j < G; j++) {
            double b = LV_B(j);
            if (b != b) { w = j; break; }
            if (j == 0 || b > best) { best = b; w = j; }
        }
        long jb = -1, db = G + 2;
        for (long j = 0; j < G; j++) { /* the nearest angle to w not beyond the bound */
            double b = LV_B(j);
            long d = b <= 0 ? (j > w ? j - w : w - j) : G + 1;
            if (d < db) { db = d; jb = j; }
        }
        if (db <= G) {
            long k = jb < w ? jb + 1 : jb - 1;
            if (k < 0) k = 0;
            if (k > G - 1) k = G - 1;
            double bj = LV_B(jb), bk = LV_B(k);
            double f = bk != bj ? -bj / (bk - bj) : 0.5;
            if (f < 0) f = 0; else if (f > 1) f = 1;
            edge[r] = t[jb] + f * (t[k] - t[jb]);
        } else
            edge[r] = NAN;
        long wl = w > 0 ? w - 1 : 0, wr = w < G - 1 ? w + 1 : G - 1;
        double bl = LV_B(wl), bw = LV_B(w), br = LV_B(wr);
        double c = bl - 2 * bw + br, d = 0.0;
        if (w > 0 && w < G - 1 && c < 0) d = 0.5 * (bl - br) / c;
        if (d < -1) d = -1; else if (d > 1) d = 1;
        worst[r] = t[w] + d * (t[1] - t[0]);
#undef LV_B
    }
}

int sc_nout(void) { return NOUT; }
int sc_abi(void) { return KERNEL_ABI; }
/* the tag of the source this library was compiled from (setup.py defines it: BLAKE2b of
 * _kernel.c and _layout.h); "" when compiled without one (the cache's copy) */
#ifndef SC_SOURCE_TAG
#define SC_SOURCE_TAG ""
#endif
const char *sc_source_tag(void) { return SC_SOURCE_TAG; }
/* every layout constant shared with softclose/simulation/kernel/layout.py, as one string
 * (checked at load) */
const char *sc_layout(void) { return LAYOUT; }

static struct PyModuleDef moddef = {PyModuleDef_HEAD_INIT, "_kernel",
                                    "softclose C stroke kernel (used through ctypes)", -1, NULL};
PyMODINIT_FUNC PyInit__kernel(void) { return PyModule_Create(&moddef); }
