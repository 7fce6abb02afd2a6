/*
 * softclose fast stroke kernel.
 *
 * Integrates closing strokes of the reduced lid equation
 *     M(th) th'' + 1/2 M'(th) th'^2 = -Vg'(th) - k (l(th) - l0) l'(th) - (c dd(th) + c_rot) th'
 * for a batch of designs p = (k, l0, c, c_rot), with the geometric coefficients read from
 * a table of cubic Hermite pieces (built in Python from the CasADi model and its exact
 * derivatives). One fixed-step method per call, given by a Butcher tableau:
 *     kind 0: explicit Runge-Kutta, kind 1: implicit Runge-Kutta (Newton),
 *     kind 2: symplectic Euler (Euler-Cromer: velocity first).
 * Events are located by a last step of solved length (Newton on the step length), so
 * their accuracy is that of the method itself; the same for the peak tip speed and the
 * lowest angle of a stroke that turns back. Nothing is integrated past the event.
 *
 * No Python API is used by the solver; the module init only lets setuptools build it.
 */
#include <Python.h>
#include <math.h>
#include <string.h>

#define NC 8 /* M, dM, Vg, dVg, l, dl, dd, tau */
enum { C_M, C_DM, C_VG, C_DVG, C_L, C_DL, C_DD, C_TAU };
#define SMAX 4

/* outputs per design */
enum { O_STATUS, O_TIME, O_THD, O_TIP, O_PEAK, O_LMIN, O_LMAX, O_NSTEP, O_EDRIFT, O_THMIN,
       O_THDMAX, /* max of theta' over the nodes after release (> 0: the lid moved up) */
       O_THMAX,  /* highest angle of the stroke (above theta0 when a spring pushes it open) */
       NOUT };
/* status codes */
enum { S_CLOSED = 0, S_OPEN = 1, S_UNSTABLE = 2, S_RANGE = 3, S_NONFINITE = 4, S_NEWTON = 5 };

typedef struct {
    const double *cc; /* ncell * NC * 4 cubic coefficients in the local variable s in [0, 1] */
    int ncell;
    double lo, h, inv_h;
} Table;

typedef struct {
    int kind, s;
    double A[SMAX][SMAX], b[SMAX], c[SMAX];
} Method;

typedef struct { double k, l0, c, cr; } Par;

/* the table cell holding th and the local variable s in [0, 1]; NULL outside the table */
static inline const double *cell(const Table *T, double th, double *s)
{
    double x = (th - T->lo) * T->inv_h;
    if (!(x >= 0.0 && x <= (double)T->ncell)) return NULL;
    int i = (int)x;
    if (i >= T->ncell) i = T->ncell - 1;
    *s = x - i;
    return T->cc + (size_t)i * NC * 4;
}

/* coefficient values v[NC] and theta-derivatives dv[NC] (dv may be NULL) */
static inline int tab_eval(const Table *T, double th, double *v, double *dv)
{
    double s;
    const double *q = cell(T, th, &s);
    if (!q) return 1;
    for (int j = 0; j < NC; j++, q += 4) {
        v[j] = q[0] + s * (q[1] + s * (q[2] + s * q[3]));
        if (dv) dv[j] = (q[1] + s * (2.0 * q[2] + s * 3.0 * q[3])) * T->inv_h;
    }
    return 0;
}

/* the hot path: theta'' only (the six coefficients it needs, no derivatives) */
static inline int rhs_fast(const Table *T, const Par *p, double th, double thd, double *thdd)
{
    double s;
    const double *q = cell(T, th, &s);
    if (!q) return 1;
#define CUB(j) (q[4 * (j)] + s * (q[4 * (j) + 1] + s * (q[4 * (j) + 2] + s * q[4 * (j) + 3])))
    double M = CUB(C_M), dM = CUB(C_DM), dVg = CUB(C_DVG), l = CUB(C_L), dl = CUB(C_DL),
           dd = CUB(C_DD);
#undef CUB
    double damp = p->c * dd + p->cr;
    double N = -dVg - p->k * (l - p->l0) * dl - 0.5 * dM * thd * thd - damp * thd;
    *thdd = N / M;
    return 0;
}

/* theta'' and, if J != NULL, J = (d th''/d th, d th''/d th') */
static inline int rhs(const Table *T, const Par *p, double th, double thd, double *thdd, double *J)
{
    double v[NC], dv[NC];
    if (tab_eval(T, th, v, J ? dv : NULL)) return 1;
    double damp = p->c * v[C_DD] + p->cr;
    double N = -v[C_DVG] - p->k * (v[C_L] - p->l0) * v[C_DL] - 0.5 * v[C_DM] * thd * thd - damp * thd;
    *thdd = N / v[C_M];
    if (J) {
        double Nth = -dv[C_DVG] - p->k * (dv[C_L] * v[C_DL] + (v[C_L] - p->l0) * dv[C_DL])
                     - 0.5 * dv[C_DM] * thd * thd - p->c * dv[C_DD] * thd;
        J[0] = (Nth - *thdd * dv[C_M]) / v[C_M];
        J[1] = (-v[C_DM] * thd - damp) / v[C_M];
    }
    return 0;
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
            if (rhs(T, p, y0, y1, &K1[i], NULL)) return S_RANGE;
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
    if (tab_eval(T, th, v, dv)) return 1;
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
        if (!tab_eval(T, ends[e], v, NULL)) {
            if (v[C_L] < *lmin) *lmin = v[C_L];
            if (v[C_L] > *lmax) *lmax = v[C_L];
        }
    int i0 = (int)floor((a - T->lo) / T->h), i1 = (int)floor((b - T->lo) / T->h);
    if (i0 < 0) i0 = 0;
    if (i1 > T->ncell - 1) i1 = T->ncell - 1;
    for (int i = i0; i <= i1; i++) {
        const double *q = T->cc + (size_t)i * NC * 4 + C_L * 4;
        /* roots of q1 + 2 q2 s + 3 q3 s^2 */
        double A = 3 * q[3], B = 2 * q[2], C = q[1], r[2];
        int nr = 0;
        if (fabs(A) < 1e-300) { if (B != 0) r[nr++] = -C / B; }
        else {
            double D = B * B - 4 * A * C;
            if (D >= 0) { double sq = sqrt(D); r[nr++] = (-B + sq) / (2 * A); r[nr++] = (-B - sq) / (2 * A); }
        }
        for (int j = 0; j < nr; j++) {
            double th = T->lo + (i + r[j]) * T->h;
            if (r[j] < 0 || r[j] > 1 || th < a || th > b) continue;
            double l = q[0] + r[j] * (q[1] + r[j] * (q[2] + r[j] * q[3]));
            if (l < *lmin) *lmin = l;
            if (l > *lmax) *lmax = l;
        }
    }
}

/* ---- the stroke loop ----------------------------------------------------------------
 * A stroke is a small state machine (Lane). Several strokes are advanced in lockstep
 * ("lanes"): their RK stages are independent, so the CPU overlaps the table look-ups and
 * divisions of one lane with those of the others instead of waiting on one dependent
 * chain. Each lane's bookkeeping after a step (event, peak, energy) is the scalar code of
 * one stroke; a finished lane is refilled with the next design. Results do not depend on
 * the lane count. The method's first explicit stage at a node is the theta'' already
 * computed there (FSAL), and the tip speed, its rate, theta'' and the energy at a node
 * come from one table look-up. */
#define LANES 4

typedef struct {
    Par p;
    double e_tol, *out;
    double t, th, thd, th_min, th_max, thp, thdp, hp; /* hp: length of the previous step */
    double gp, g, dg, a, peak, E0, Emax;      /* tip speed at previous/current node, ...  */
    double thd_max;                           /* max theta' over the nodes after t = 0 */
    long n, nt, traj_cap;
    double *traj;
    int status;
} Lane;

/* theta'', tip speed g = tau |th'|, its rate dg and the energy at a node: one look-up */
static inline int node_eval(const Table *T, const Par *p, double th, double thd,
                            double *a, double *g, double *dg, double *E)
{
    double s;
    const double *q = cell(T, th, &s);
    if (!q) return 1;
#define CUB(j) (q[4 * (j)] + s * (q[4 * (j) + 1] + s * (q[4 * (j) + 2] + s * q[4 * (j) + 3])))
    double M = CUB(C_M), dM = CUB(C_DM), Vg = CUB(C_VG), dVg = CUB(C_DVG), l = CUB(C_L),
           dl = CUB(C_DL), dd = CUB(C_DD), tau = CUB(C_TAU);
#undef CUB
    const double *qt = q + 4 * C_TAU;
    double dtau = (qt[1] + s * (2.0 * qt[2] + s * 3.0 * qt[3])) * T->inv_h;
    double damp = p->c * dd + p->cr;
    double N = -dVg - p->k * (l - p->l0) * dl - 0.5 * dM * thd * thd - damp * thd;
    double acc = N / M;
    double sg = thd >= 0 ? 1.0 : -1.0;
    *a = acc;
    *g = tau * fabs(thd);
    *dg = sg * (dtau * thd * thd + tau * acc);
    double dl0 = l - p->l0;
    *E = 0.5 * M * thd * thd + Vg + 0.5 * p->k * dl0 * dl0;
    return 0;
}

static inline void lane_record(Lane *L)
{
    if (L->traj && L->nt < L->traj_cap) {
        L->traj[3 * L->nt] = L->t; L->traj[3 * L->nt + 1] = L->th; L->traj[3 * L->nt + 2] = L->thd;
        L->nt++;
    }
}

/* start a stroke from rest at th0; returns 1 if it is already over (not tabulated) */
static int lane_start(const Table *T, Lane *L, const double *d, double *out, double th0,
                      double *traj, long traj_cap)
{
    L->p.k = d[0]; L->p.l0 = d[1]; L->p.c = d[2]; L->p.cr = d[3]; L->e_tol = d[4];
    L->out = out;
    L->t = 0.0; L->th = th0; L->thd = 0.0; L->th_min = th0; L->th_max = th0;
    L->thp = th0; L->thdp = 0.0; L->hp = 0.0;
    L->gp = 0.0; L->g = 0.0; L->dg = 0.0; L->peak = 0.0; L->a = 0.0;
    L->n = 0; L->nt = 0; L->traj = traj; L->traj_cap = traj_cap; L->thd_max = -INFINITY;
    L->status = S_OPEN;
    for (int j = 0; j < NOUT; j++) out[j] = NAN;
    lane_record(L);
    double E0;
    if (node_eval(T, &L->p, th0, 0.0, &L->a, &L->g, &L->dg, &E0) || !isfinite(E0)) {
        L->E0 = L->Emax = NAN; L->status = S_RANGE; return 1;
    }
    L->E0 = L->Emax = E0;
    return 0;
}

static void lane_finish(const Table *T, Lane *L, double th0)
{
    double *out = L->out;
    out[O_STATUS] = L->status;
    out[O_PEAK] = L->peak;
    out[O_NSTEP] = (double)L->n;
    out[O_EDRIFT] = L->Emax - L->E0;
    out[O_THMIN] = L->th_min;
    out[O_THDMAX] = L->thd_max;
    out[O_THMAX] = L->th_max;
    if (L->status == S_CLOSED || L->status == S_OPEN) {
        double lmin, lmax;
        l_extremes(T, L->th_min, L->th_max, &lmin, &lmax);
        out[O_LMIN] = lmin; out[O_LMAX] = lmax;
    }
    if (L->status != S_CLOSED) { out[O_TIME] = NAN; out[O_THD] = NAN; out[O_TIP] = NAN; }
}

/* bookkeeping after a step of length h to (th1, thd1) with step status st; 1 = over */
static int lane_after_step(const Table *T, const Method *m, Lane *L, double h, double th1,
                           double thd1, int st, double thc)
{
    const Par *p = &L->p;
    double th = L->th, thd = L->thd;
    L->n++;
    if (st) { L->status = st; return 1; }
    if (!isfinite(th1) || !isfinite(thd1)) { L->status = S_NONFINITE; return 1; }
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
        double g = L->g, dg = L->dg;
        if (g > L->peak) L->peak = g;
        if (L->n > 1 && g >= L->gp && g > gi)
            refine_extremum(T, m, p, 0, L->thp, L->thdp, L->hp + tau, &L->peak);
        else if (dg > 0 && dgi < 0)
            refine_extremum(T, m, p, 0, th, thd, tau, &L->peak);
        if (gi > L->peak) L->peak = gi;
        if (y1 > L->thd_max) L->thd_max = y1;
        L->t += tau; L->th = thc; L->thd = y1; L->th_min = thc; L->status = S_CLOSED;
        L->out[O_TIME] = L->t; L->out[O_THD] = y1; L->out[O_TIP] = gi;
        lane_record(L);
        return 1;
    }
    /* the new node: theta'' (the next step's first stage), tip speed, its rate, energy */
    double a1, g1, dg1, E1;
    if (node_eval(T, p, th1, thd1, &a1, &g1, &dg1, &E1)) { L->status = S_RANGE; return 1; }
    /* interior extrema at the node we are leaving (t): tip-speed peak, lowest angle */
    if (L->n > 1 && L->g >= L->gp && L->g > g1)
        refine_extremum(T, m, p, 0, L->thp, L->thdp, L->hp + h, &L->peak);
    if (g1 > L->peak) L->peak = g1;
    if (thd < 0 && thd1 >= 0) { /* turned back: lowest angle inside this step */
        double lowest = th1 < th ? th1 : th;
        refine_extremum(T, m, p, 1, th, thd, h, &lowest);
        if (lowest < L->th_min) L->th_min = lowest;
    }
    if (thd > 0 && thd1 <= 0) { /* turned down: highest angle inside this step */
        double neg = -(th1 > th ? th1 : th);
        refine_extremum(T, m, p, 2, th, thd, h, &neg);
        if (-neg > L->th_max) L->th_max = -neg;
    }
    if (th1 < L->th_min) L->th_min = th1;
    if (th1 > L->th_max) L->th_max = th1;
    if (thd1 > L->thd_max) L->thd_max = thd1;
    if (!isfinite(E1)) { L->status = S_RANGE; return 1; }
    if (E1 > L->Emax) L->Emax = E1;
    if (E1 - L->E0 > L->e_tol) {
        L->status = S_UNSTABLE; L->t += h; L->th = th1; L->thd = thd1; return 1;
    }
    L->gp = L->g; L->thp = th; L->thdp = thd; L->hp = h;
    L->g = g1; L->dg = dg1; L->a = a1;
    L->t += h; L->th = th1; L->thd = thd1;
    lane_record(L);
    return 0;
}

/* one explicit RK step for the active lanes; s is a literal at the hot call (unrolled) */
static inline __attribute__((always_inline)) void
explicit_lanes(const Table *T, const Method *m, const int s, Lane *lanes, const int *act,
               int na, const double *hh, double *y0, double *y1, int *st)
{
    double K0[LANES][SMAX], K1[LANES][SMAX];
    for (int q = 0; q < na; q++) {
        Lane *L = &lanes[act[q]];
        K0[q][0] = L->thd; K1[q][0] = L->a; st[q] = 0;
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
            if (rhs_fast(T, &L->p, z0, z1, &K1[q][i])) { K1[q][i] = NAN; st[q] = S_RANGE; }
        }
    }
    for (int q = 0; q < na; q++) {
        Lane *L = &lanes[act[q]];
        double h = hh[act[q]], z0 = L->th, z1 = L->thd;
        for (int i = 0; i < s; i++) { z0 += h * m->b[i] * K0[q][i]; z1 += h * m->b[i] * K1[q][i]; }
        y0[q] = z0; y1[q] = z1;
    }
}

/* n strokes (rows of design: k, l0, c, c_rot, e_tol) into out (n x NOUT); with traj
 * (n must be 1) the rows (t, th, thd) of every node */
static void strokes(const Table *T, const Method *m, double dt, double t_max, double th0,
                    double thc, long n, const double *design, double *out,
                    double *traj, long traj_cap, long *traj_len)
{
    Lane lanes[LANES];
    int used[LANES] = {0};
    long next = 0;
    int nlanes = traj ? 1 : LANES;
    const int s = m->s;
    for (;;) {
        int act[LANES], na = 0;
        double hh[LANES];
        for (int k = 0; k < nlanes; k++) {
            for (;;) {
                if (used[k]) {
                    Lane *L = &lanes[k];
                    double h = dt < t_max - L->t ? dt : t_max - L->t;
                    if (L->t < t_max && h > 1e-15 * t_max) { hh[k] = h; break; }
                    lane_finish(T, L, th0); /* ran to t_max without closing */
                    if (traj_len) *traj_len = L->nt;
                    used[k] = 0;
                }
                if (next >= n) break;
                used[k] = 1;
                if (lane_start(T, &lanes[k], design + 5 * next, out + NOUT * next, th0, traj,
                               traj_cap)) {
                    lane_finish(T, &lanes[k], th0);
                    if (traj_len) *traj_len = lanes[k].nt;
                    used[k] = 0;
                }
                next++;
            }
            if (used[k]) act[na++] = k;
        }
        if (na == 0) break;
        double y0[LANES], y1[LANES];
        int st[LANES];
        if (m->kind == 0) { /* explicit RK, lanes interleaved, first stage from the node */
            if (s == 4) explicit_lanes(T, m, 4, lanes, act, na, hh, y0, y1, st);
            else explicit_lanes(T, m, s, lanes, act, na, hh, y0, y1, st);
        } else if (m->kind == 2) { /* symplectic Euler from the node's theta'' */
            for (int q = 0; q < na; q++) {
                Lane *L = &lanes[act[q]];
                double h = hh[act[q]];
                y1[q] = L->thd + h * L->a;
                y0[q] = L->th + h * y1[q];
                st[q] = 0;
            }
        } else {
            for (int q = 0; q < na; q++) {
                Lane *L = &lanes[act[q]];
                st[q] = step(T, m, &L->p, hh[act[q]], L->th, L->thd, &y0[q], &y1[q]);
            }
        }
        for (int q = 0; q < na; q++) {
            int k = act[q];
            if (lane_after_step(T, m, &lanes[k], hh[k], y0[q], y1[q], st[q], thc)) {
                lane_finish(T, &lanes[k], th0);
                if (traj_len) *traj_len = lanes[k].nt;
                used[k] = 0;
            }
        }
    }
}

/* ---- exported entry points (called through ctypes; the GIL is released) ---- */

static void make(const double *tab_meta, const double *cc, const double *tableau,
                 Table *T, Method *m)
{
    T->cc = cc; T->ncell = (int)tab_meta[0]; T->lo = tab_meta[1]; T->h = tab_meta[2];
    T->inv_h = 1.0 / T->h;
    m->kind = (int)tableau[0]; m->s = (int)tableau[1];
    int s = m->s;
    for (int i = 0; i < s; i++) {
        for (int j = 0; j < s; j++) m->A[i][j] = tableau[2 + i * s + j];
        m->b[i] = tableau[2 + s * s + i];
        m->c[i] = tableau[2 + s * s + s + i];
    }
}

/* strokes for n designs (rows of `design`: k, l0, c, c_rot, e_tol); out: n x NOUT */
void sc_strokes(const double *tab_meta, const double *cc, const double *tableau,
                double dt, double t_max, double th0, double thc,
                long n, const double *design, double *out)
{
    Table T; Method m;
    make(tab_meta, cc, tableau, &T, &m);
    strokes(&T, &m, dt, t_max, th0, thc, n, design, out, NULL, 0, NULL);
}

/* one stroke with its trajectory */
void sc_stroke_traj(const double *tab_meta, const double *cc, const double *tableau,
                    double dt, double t_max, double th0, double thc, const double *design,
                    double *out, double *traj, long traj_cap, long *traj_len)
{
    Table T; Method m;
    make(tab_meta, cc, tableau, &T, &m);
    *traj_len = 0;
    strokes(&T, &m, dt, t_max, th0, thc, 1, design, out, traj, traj_cap, traj_len);
}

/* one step (for tests): x1 = step(x0, h) */
int sc_step(const double *tab_meta, const double *cc, const double *tableau,
            const double *design, double h, const double *x0, double *x1)
{
    Table T; Method m;
    make(tab_meta, cc, tableau, &T, &m);
    Par p = {design[0], design[1], design[2], design[3]};
    return step(&T, &m, &p, h, x0[0], x0[1], &x1[0], &x1[1]);
}

int sc_nout(void) { return NOUT; }

static struct PyModuleDef moddef = {PyModuleDef_HEAD_INIT, "_kernel",
                                    "softclose C stroke kernel (used through ctypes)", -1, NULL};
PyMODINIT_FUNC PyInit__kernel(void) { return PyModule_Create(&moddef); }
