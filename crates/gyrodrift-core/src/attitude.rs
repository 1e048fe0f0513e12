//! Attitude mathematics: vectors, direction cosine matrices (DCM), quaternions, rotation vectors and
//! Euler angles.
//!
//! Conventions (the same as PSINS, Yan Gongmin, "Strapdown inertial navigation algorithm and integrated
//! navigation principles", 2016, ch. 2):
//! - Navigation frame n: local-level East-North-Up (ENU). Body frame b: Right-Forward-Up.
//! - Quaternions are Hamilton quaternions, scalar first: q = [q0, q1, q2, q3] = [cos(a/2), u sin(a/2)].
//!   `q_b^n` rotates body-frame coordinates into navigation-frame coordinates: v^n = q_b^n o v^b o q_b^n*.
//! - `C_b^n` is the DCM of the same rotation: v^n = C_b^n v^b.
//! - Euler angles (pitch theta, roll gamma, yaw psi), rotation order z-x-y (PSINS `a2mat`):
//!   C_b^n = Rz(psi) Rx(theta) Ry(gamma), where Rz, Rx, Ry are right-handed rotations of coordinates
//!   (active rotations of vectors). Yaw is positive counter-clockwise about Up (yaw = 0: Forward points
//!   North; yaw = +90 deg: Forward points West). Pitch is positive nose up, roll positive right wing down
//!   (rotation about Forward).
//! - Rotation vector phi: the rotation by |phi| about phi/|phi|; q = [cos(|phi|/2), phi/|phi| sin(|phi|/2)].

/// A 3-vector [x, y, z].
pub type Vec3 = [f64; 3];
/// A 3x3 matrix, row-major: `m[row][col]`.
pub type Mat3 = [[f64; 3]; 3];
/// A Hamilton quaternion, scalar first [q0, q1, q2, q3].
pub type Quat = [f64; 4];

/// Identity quaternion.
pub const QUAT_IDENTITY: Quat = [1.0, 0.0, 0.0, 0.0];

// ---------------------------------------------------------------- vectors and matrices

#[inline(always)]
pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline(always)]
pub fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
pub fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

/// Cross product a x b.
#[inline(always)]
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// m v.
#[inline(always)]
pub fn mat_vec(m: &Mat3, v: Vec3) -> Vec3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// m' v (the transpose applied, e.g. C_n^b v = (C_b^n)' v).
#[inline(always)]
pub fn mat_t_vec(m: &Mat3, v: Vec3) -> Vec3 {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}

/// a b.
#[inline]
pub fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

/// m'.
#[inline]
pub fn transpose(m: &Mat3) -> Mat3 {
    [
        [m[0][0], m[1][0], m[2][0]],
        [m[0][1], m[1][1], m[2][1]],
        [m[0][2], m[1][2], m[2][2]],
    ]
}

/// Rotation about x by angle a \[rad\] (active, right-handed).
pub fn rot_x(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// Rotation about y by angle a \[rad\] (active, right-handed).
pub fn rot_y(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// Rotation about z by angle a \[rad\] (active, right-handed; positive counter-clockwise seen from +z).
pub fn rot_z(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

// ---------------------------------------------------------------- Euler angles

/// Attitude as Euler angles \[rad\]: C_b^n = Rz(yaw) Rx(pitch) Ry(roll) (PSINS order), yaw CCW about Up.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Euler {
    pub pitch: f64,
    pub roll: f64,
    pub yaw: f64,
}

/// C_b^n from Euler angles: C_b^n = Rz(yaw) Rx(pitch) Ry(roll) (PSINS `a2mat`).
pub fn euler_to_dcm(e: Euler) -> Mat3 {
    mat_mul(&rot_z(e.yaw), &mat_mul(&rot_x(e.pitch), &rot_y(e.roll)))
}

/// Euler angles from C_b^n (PSINS `m2att`): pitch = asin(C32), roll = atan2(-C31, C33),
/// yaw = atan2(-C12, C22). Pitch in [-pi/2, pi/2], roll and yaw in (-pi, pi].
/// Near pitch = +-90 deg (|C32| > 1 - 1e-12) roll is set to zero and yaw taken from the first two rows.
pub fn dcm_to_euler(c: &Mat3) -> Euler {
    let s = c[2][1].clamp(-1.0, 1.0);
    let pitch = s.asin();
    if s.abs() <= 1.0 - 1e-12 {
        Euler {
            pitch,
            roll: (-c[2][0]).atan2(c[2][2]),
            yaw: (-c[0][1]).atan2(c[1][1]),
        }
    } else {
        // Gimbal lock: C = Rz(yaw) Rx(+-90) Ry(roll) leaves only yaw +- roll; put it all in yaw.
        Euler {
            pitch,
            roll: 0.0,
            yaw: c[1][0].atan2(c[0][0]),
        }
    }
}

/// q_b^n from Euler angles: q = qz(yaw) o qx(pitch) o qy(roll) (PSINS `a2qua`).
pub fn euler_to_quat(e: Euler) -> Quat {
    let (sp, cp) = (0.5 * e.pitch).sin_cos();
    let (sr, cr) = (0.5 * e.roll).sin_cos();
    let (sy, cy) = (0.5 * e.yaw).sin_cos();
    let qz = [cy, 0.0, 0.0, sy];
    let qx = [cp, sp, 0.0, 0.0];
    let qy = [cr, 0.0, sr, 0.0];
    quat_mul(quat_mul(qz, qx), qy)
}

/// Euler angles from q_b^n.
pub fn quat_to_euler(q: Quat) -> Euler {
    dcm_to_euler(&quat_to_dcm(q))
}

// ---------------------------------------------------------------- quaternions

/// Hamilton product p o q (scalar first): the rotation q followed by p when composing frames,
/// e.g. q_b^i = q_n^i o q_b^n.
#[inline(always)]
pub fn quat_mul(p: Quat, q: Quat) -> Quat {
    [
        p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3],
        p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2],
        p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1],
        p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0],
    ]
}

/// Conjugate q* (the inverse of a unit quaternion).
#[inline(always)]
pub fn quat_conj(q: Quat) -> Quat {
    [q[0], -q[1], -q[2], -q[3]]
}

/// q / |q|.
#[inline(always)]
pub fn quat_normalize(q: Quat) -> Quat {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let inv = 1.0 / n;
    [q[0] * inv, q[1] * inv, q[2] * inv, q[3] * inv]
}

/// Rotate a vector: q o [0, v] o q* (= C(q) v), without forming the DCM.
#[inline(always)]
pub fn quat_rotate(q: Quat, v: Vec3) -> Vec3 {
    // v' = v + 2 q0 (u x v) + 2 u x (u x v), u = vector part.
    let u = [q[1], q[2], q[3]];
    let t = scale(cross(u, v), 2.0);
    add(add(v, scale(t, q[0])), cross(u, t))
}

/// DCM of a unit quaternion (PSINS `q2mat`).
pub fn quat_to_dcm(q: Quat) -> Mat3 {
    let (q0, q1, q2, q3) = (q[0], q[1], q[2], q[3]);
    let (q11, q12, q13, q14) = (q0 * q0, q0 * q1, q0 * q2, q0 * q3);
    let (q22, q23, q24) = (q1 * q1, q1 * q2, q1 * q3);
    let (q33, q34) = (q2 * q2, q2 * q3);
    let q44 = q3 * q3;
    [
        [q11 + q22 - q33 - q44, 2.0 * (q23 - q14), 2.0 * (q24 + q13)],
        [2.0 * (q23 + q14), q11 - q22 + q33 - q44, 2.0 * (q34 - q12)],
        [2.0 * (q24 - q13), 2.0 * (q34 + q12), q11 - q22 - q33 + q44],
    ]
}

/// Unit quaternion (with q0 >= 0) of a proper orthogonal DCM (Shepperd's method, robust for any angle).
pub fn dcm_to_quat(c: &Mat3) -> Quat {
    let tr = c[0][0] + c[1][1] + c[2][2];
    let q = if tr > c[0][0].max(c[1][1]).max(c[2][2]) {
        let s = 2.0 * (1.0 + tr).sqrt();
        [
            0.25 * s,
            (c[2][1] - c[1][2]) / s,
            (c[0][2] - c[2][0]) / s,
            (c[1][0] - c[0][1]) / s,
        ]
    } else if c[0][0] >= c[1][1] && c[0][0] >= c[2][2] {
        let s = 2.0 * (1.0 + c[0][0] - c[1][1] - c[2][2]).sqrt();
        [
            (c[2][1] - c[1][2]) / s,
            0.25 * s,
            (c[0][1] + c[1][0]) / s,
            (c[0][2] + c[2][0]) / s,
        ]
    } else if c[1][1] >= c[2][2] {
        let s = 2.0 * (1.0 + c[1][1] - c[0][0] - c[2][2]).sqrt();
        [
            (c[0][2] - c[2][0]) / s,
            (c[0][1] + c[1][0]) / s,
            0.25 * s,
            (c[1][2] + c[2][1]) / s,
        ]
    } else {
        let s = 2.0 * (1.0 + c[2][2] - c[0][0] - c[1][1]).sqrt();
        [
            (c[1][0] - c[0][1]) / s,
            (c[0][2] + c[2][0]) / s,
            (c[1][2] + c[2][1]) / s,
            0.25 * s,
        ]
    };
    let q = quat_normalize(q);
    if q[0] < 0.0 {
        [-q[0], -q[1], -q[2], -q[3]]
    } else {
        q
    }
}

// ---------------------------------------------------------------- rotation vectors

/// Quaternion of a rotation vector phi \[rad\] (PSINS `rv2q`), exact:
/// q = [cos(|phi|/2), phi sin(|phi|/2)/|phi|].
/// For |phi| < 0.05 rad the Taylor series of cos(x) and sin(x)/x (x = |phi|/2) to x^6 is used; its truncation
/// error is below 5e-18, i.e. exact in double precision, and it needs no trigonometric call (the navigator
/// calls this once per sample).
#[inline]
pub fn rotvec_to_quat(phi: Vec3) -> Quat {
    let n2 = dot(phi, phi);
    let (c, s_over_n) = if n2 < 0.05 * 0.05 {
        let x2 = 0.25 * n2; // (|phi|/2)^2
        let c = 1.0 - x2 * (0.5 - x2 * (1.0 / 24.0 - x2 * (1.0 / 720.0)));
        // sin(x)/|phi| = 0.5 sin(x)/x
        let s = 0.5 * (1.0 - x2 * (1.0 / 6.0 - x2 * (1.0 / 120.0 - x2 * (1.0 / 5040.0))));
        (c, s)
    } else {
        let n = n2.sqrt();
        let (s, c) = (0.5 * n).sin_cos();
        (c, s / n)
    };
    [c, phi[0] * s_over_n, phi[1] * s_over_n, phi[2] * s_over_n]
}

/// Rotation vector of a unit quaternion (PSINS `q2rv`), angle in [0, pi]:
/// phi = 2 atan2(|v|, q0) v / |v| (sign of q chosen with q0 >= 0). Series of atan(x)/x for small x = |v|/q0.
pub fn quat_to_rotvec(q: Quat) -> Vec3 {
    let q = if q[0] < 0.0 { [-q[0], -q[1], -q[2], -q[3]] } else { q };
    let v = [q[1], q[2], q[3]];
    let n = norm(v);
    let f = if n < 1e-3 * q[0] {
        let x2 = (n / q[0]).powi(2);
        2.0 / q[0] * (1.0 - x2 * (1.0 / 3.0 - x2 * (1.0 / 5.0 - x2 / 7.0)))
    } else {
        2.0 * n.atan2(q[0]) / n
    };
    scale(v, f)
}

/// Rotation vector of a DCM (via the quaternion).
pub fn dcm_to_rotvec(c: &Mat3) -> Vec3 {
    quat_to_rotvec(dcm_to_quat(c))
}

/// DCM of a rotation vector (Rodrigues, via the quaternion).
pub fn rotvec_to_dcm(phi: Vec3) -> Mat3 {
    quat_to_dcm(rotvec_to_quat(phi))
}

/// Wrap an angle to (-pi, pi].
#[inline]
pub fn wrap_pi(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let mut w = a.rem_euclid(TAU);
    if w > PI {
        w -= TAU;
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn mat_close(a: &Mat3, b: &Mat3, tol: f64) -> bool {
        (0..3).all(|i| (0..3).all(|j| (a[i][j] - b[i][j]).abs() < tol))
    }

    fn quat_close(a: Quat, b: Quat, tol: f64) -> bool {
        // q and -q are the same rotation.
        let d1 = (0..4).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max);
        let d2 = (0..4).map(|i| (a[i] + b[i]).abs()).fold(0.0, f64::max);
        d1.min(d2) < tol
    }

    const EULERS: [[f64; 3]; 6] = [
        [0.1, -0.2, 0.3],
        [-0.7, 1.2, -2.9],
        [1.3, 3.0, 3.1],
        [0.0, 0.0, -1.0],
        [-1.5, -3.1, 0.01],
        [0.4, 2.0, PI],
    ];

    #[test]
    fn euler_dcm_round_trip_and_explicit_elements() {
        for [p, r, y] in EULERS {
            let e = Euler {
                pitch: p,
                roll: r,
                yaw: y,
            };
            let c = euler_to_dcm(e);
            // Closed form of the third row and of C12, C22 for Rz(y) Rx(p) Ry(r).
            assert!((c[2][1] - p.sin()).abs() < 1e-15);
            assert!((c[2][0] + p.cos() * r.sin()).abs() < 1e-15);
            assert!((c[2][2] - p.cos() * r.cos()).abs() < 1e-15);
            assert!((c[0][1] + y.sin() * p.cos()).abs() < 1e-15);
            assert!((c[1][1] - y.cos() * p.cos()).abs() < 1e-15);
            let back = dcm_to_euler(&c);
            assert!((back.pitch - p).abs() < 1e-12);
            assert!(wrap_pi(back.roll - r).abs() < 1e-12, "{back:?}");
            assert!(wrap_pi(back.yaw - y).abs() < 1e-12, "{back:?}");
            // Quaternion route agrees with the DCM route.
            assert!(mat_close(&quat_to_dcm(euler_to_quat(e)), &c, 1e-15));
            assert!(quat_close(dcm_to_quat(&c), euler_to_quat(e), 1e-14));
        }
    }

    #[test]
    fn yaw_is_counter_clockwise_about_up() {
        // yaw = +90 deg: the body Forward axis (y) points West (-x in ENU).
        let c = euler_to_dcm(Euler {
            pitch: 0.0,
            roll: 0.0,
            yaw: FRAC_PI_2,
        });
        let fwd = mat_vec(&c, [0.0, 1.0, 0.0]);
        assert!((fwd[0] + 1.0).abs() < 1e-15 && fwd[1].abs() < 1e-15);
        // Positive pitch raises the nose: Forward gets a positive Up component.
        let c = euler_to_dcm(Euler {
            pitch: 0.1,
            roll: 0.0,
            yaw: 0.0,
        });
        assert!((mat_vec(&c, [0.0, 1.0, 0.0])[2] - 0.1f64.sin()).abs() < 1e-15);
    }

    #[test]
    fn dcm_is_orthonormal_and_transpose_is_inverse() {
        for [p, r, y] in EULERS {
            let c = euler_to_dcm(Euler {
                pitch: p,
                roll: r,
                yaw: y,
            });
            let i = mat_mul(&c, &transpose(&c));
            assert!(mat_close(
                &i,
                &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                1e-15
            ));
            let v = [0.3, -1.1, 2.0];
            let back = mat_t_vec(&c, mat_vec(&c, v));
            assert!(norm(sub(back, v)) < 1e-15);
        }
    }

    #[test]
    fn rotation_vector_round_trips_small_and_large() {
        let axes = [[1.0, 0.0, 0.0], [0.0, 0.6, 0.8], [-0.48, 0.6, 0.64]];
        for ax in axes {
            for ang in [0.0, 1e-12, 1e-7, 1e-3, 0.0499, 0.0501, 0.5, 2.0, 3.1] {
                let phi = scale(ax, ang);
                let q = rotvec_to_quat(phi);
                // Closed form.
                let exact = [
                    (0.5 * ang).cos(),
                    ax[0] * (0.5 * ang).sin(),
                    ax[1] * (0.5 * ang).sin(),
                    ax[2] * (0.5 * ang).sin(),
                ];
                assert!(quat_close(q, exact, 2e-16 * (1.0 + ang)), "{ang}: {q:?} vs {exact:?}");
                let back = quat_to_rotvec(q);
                assert!(norm(sub(back, phi)) < 1e-15 * (1.0 + 10.0 * ang), "{ang}: {back:?}");
                // The DCM is the Rodrigues formula: rotating the axis leaves it fixed, and a vector
                // perpendicular to it turns by ang.
                let c = rotvec_to_dcm(phi);
                assert!(norm(sub(mat_vec(&c, ax), ax)) < 1e-15);
                let perp = cross(ax, [0.0, 0.0, 1.0]);
                let perp = if norm(perp) < 1e-9 {
                    [0.0, 1.0, 0.0]
                } else {
                    scale(perp, 1.0 / norm(perp))
                };
                let cosang = dot(perp, mat_vec(&c, perp));
                assert!((cosang - ang.cos()).abs() < 1e-14);
                assert!(norm(sub(dcm_to_rotvec(&c), phi)) < 1e-13);
            }
        }
    }

    #[test]
    fn composition_of_quaternions_matches_dcm_product() {
        let a = euler_to_quat(Euler {
            pitch: 0.3,
            roll: -0.4,
            yaw: 2.0,
        });
        let b = euler_to_quat(Euler {
            pitch: -1.0,
            roll: 2.5,
            yaw: -0.2,
        });
        let ab = quat_mul(a, b);
        assert!(mat_close(
            &quat_to_dcm(ab),
            &mat_mul(&quat_to_dcm(a), &quat_to_dcm(b)),
            1e-15
        ));
        let v = [1.0, 2.0, -0.5];
        assert!(norm(sub(quat_rotate(ab, v), mat_vec(&quat_to_dcm(ab), v))) < 1e-14);
        // Inverse.
        assert!(quat_close(quat_mul(a, quat_conj(a)), QUAT_IDENTITY, 1e-16));
        // Two rotations about the same axis add.
        let ax = [0.0, 0.6, 0.8];
        let q = quat_mul(rotvec_to_quat(scale(ax, 0.3)), rotvec_to_quat(scale(ax, 0.9)));
        assert!(quat_close(q, rotvec_to_quat(scale(ax, 1.2)), 1e-15));
        // Euler composition: Rz(y) Rx(p) Ry(r) as quaternions.
        assert!(mat_close(
            &rot_z(0.7),
            &quat_to_dcm(rotvec_to_quat([0.0, 0.0, 0.7])),
            1e-15
        ));
    }

    #[test]
    fn gimbal_lock_keeps_the_rotation() {
        let c = euler_to_dcm(Euler {
            pitch: FRAC_PI_2,
            roll: 0.3,
            yaw: 0.5,
        });
        let e = dcm_to_euler(&c);
        assert!(mat_close(&euler_to_dcm(e), &c, 1e-7));
    }
}
