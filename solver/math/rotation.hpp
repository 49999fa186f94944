// Rotations on SO(3): the exponential/log maps and their tangent operators.
// Every orientation in the solver is a stored rotation matrix updated by an
// incremental rotation vector through the exact exponential map (docs/design.md 3),
// so orthogonality is kept to round-off over any number of steps.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace mfbd {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// skew(a) * b == a.cross(b)
Mat3 skew(const Vec3& a);
Vec3 unskew(const Mat3& S);

// Rodrigues: exp(skew(theta)).
Mat3 expSO3(const Vec3& theta);
// Rotation vector of R, |theta| <= pi; accurate near 0 and near pi.
Vec3 logSO3(const Mat3& R);

// Tangent operator T(theta) of the exponential map, right-trivialised:
// exp(theta + d) = exp(theta) exp(T(theta) d) + O(d^2).
// (omega = T(theta) thetadot for R = exp(theta), omega in the body frame.)
Mat3 tangentSO3(const Vec3& theta);
// Its inverse, thetadot = T^-1(theta) omega; T^-1 = I + S/2 + e S^2
// (S = skew(theta), e: math/rotation_series.hpp).
Mat3 tangentSO3Inverse(const Vec3& theta);
// Its derivative applied to a fixed vector x, as a linear map of dtheta:
// d(T^-1 x) = J dtheta, or with transposed d(T^-T x) = J dtheta, where
//   J = -+ skew(x)/2 - e (skew(theta x x) + S skew(x)) + (e'/t) (S^2 x) theta^T.
Mat3 tangentSO3InverseDerivative(const Vec3& theta, const Vec3& x, bool transposed);

// One Newton step towards the polar factor, R (3I - R^T R)/2: it leaves a
// rotation unchanged to first order in its error. The state's rotations are
// updated by the exact map, R exp(theta), which keeps them orthogonal only
// up to accumulated round-off (about 1e-10 after 1e6 updates); this step
// once per accepted time step (restoreOrthogonality) removes that drift.
Mat3 polarStep(const Mat3& R);

// Re-orthonormalise a rotation matrix (polar decomposition by SVD); used only
// on data coming from outside (scene orientations), never on solver state.
Mat3 nearestRotation(const Mat3& M);

// A right-handed frame whose z axis is the given direction (x chosen stably).
Mat3 frameFromZAxis(const Vec3& z);

}  // namespace mfbd
