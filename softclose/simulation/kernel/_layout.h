/* The stroke kernel's layout, generated from the element registry and
 * softclose/simulation/kernel/layout.py by
 *     python -m softclose.simulation.kernel --write
 * Do not edit: tests/test_kernel_layout.py holds this file to the generator. */
#ifndef SOFTCLOSE_KERNEL_LAYOUT_H
#define SOFTCLOSE_KERNEL_LAYOUT_H

#define KERNEL_ABI 6 /* bumped when the exported signatures or outputs change */
/* the design-row columns: the elements' parameters (the registry's order), e_tol, m_lid */
enum { D_SPRING_K, D_SPRING_REST_LENGTH, D_DAMPER_C, D_ROTARY_DAMPER_C, D_SPRING_KIND,
       D_SPRING_PRELOAD, D_STRUT_STROKE, D_STRUT_PROGRESSION, D_TORSION_K,
       D_TORSION_FREE_ANGLE, D_DAMPER_ONE_WAY, D_FRICTION_TORQUE, D_END_DAMPER_C,
       D_END_DAMPER_ANGLE, D_STRUT_FRICTION, D_ENERGY_TOL, D_LID_MASS, NDESIGN };
/* the table's coefficients, and those that depend on the lid's mass (the first NMASS) */
#define NC 8
#define NMASS 4
enum { C_M, C_DM, C_VG, C_DVG, C_L, C_DL, C_DD, C_TAU };
/* the coordinate table's element columns (NX per power) */
#define NX 4
enum { X_PSI, X_DPSI, X_DPR2 };
/* the pose table's columns (NPOSE per power) */
#define NPOSE 8
enum { P_AX, P_AY, P_DAX, P_DAY, P_COS, P_SIN, P_USED };
/* the outputs per design row */
enum { O_STATUS, O_CLOSING_TIME, O_IMPACT_THETA_DOT, O_IMPACT_TIP_SPEED, O_PEAK_TIP_SPEED,
       O_MIN_SPRING_LENGTH, O_MAX_SPRING_LENGTH, O_STEPS, O_ENERGY_RISE, O_THETA_MIN,
       O_THETA_DOT_MAX, O_THETA_MAX, O_STOP_REASON, O_STOP_THETA, O_STOP_TIME, O_ENGAGE_TIME,
       O_ENGAGE_THETA_DOT, NOUT };
/* every layout constant above, as one string: checked by Python when it loads the kernel */
static const char LAYOUT[] =
    "abi=6;"
    "meta=ncell,lo,h,m0,rotary_at_pivot;"
    "cc=M,dM,Vg,dVg,l,dl,dd,tau;"
    "mass=M,dM,Vg,dVg;"
    "xcc=psi,dpsi,dpr2,-;"
    "pose=Ax,Ay,dAx,dAy,cos,sin,-,-;"
    "row=spring_k,spring_rest_length,damper_c,rotary_damper_c,spring_kind,"
    "spring_preload,strut_stroke,strut_progression,torsion_k,torsion_free_angle,"
    "damper_one_way,friction_torque,end_damper_c,end_damper_angle,strut_friction,"
    "energy_tol,lid_mass,spring_anchor_x,spring_anchor_y,lid_e_x,lid_e_y,"
    "dashpot_anchor_x,dashpot_anchor_y,dashpot_lid_x,dashpot_lid_y;"
    "out=status,closing_time,impact_theta_dot,impact_tip_speed,peak_tip_speed,"
    "min_spring_length,max_spring_length,steps,energy_rise,theta_min,theta_dot_max,"
    "theta_max,stop_reason,stop_theta,stop_time,engage_time,engage_theta_dot;"
    "nrng=18";

#endif
