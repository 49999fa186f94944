#include "flex/element_force_lanes.hpp"

#include <algorithm>

#include "flex/corotational_force.hpp"
#include "math/lanes.hpp"

namespace mfbd {

static_assert(kForceLanes == Lanes::kCount, "one element per lane");

namespace {

// Four elements side by side in vector lanes (math/lanes.hpp): gathered,
// computed, stored. Inlined into each of the two variants below.
[[gnu::always_inline]] inline bool elementForcesInLanes(int count, const ElementInputs elements[],
                                                        const Vec3& gravity, Vec12 f[]) {
  ElementState<Lanes> s;
  ElementConstants<Lanes> k;
  static const NodeAcceleration still;
  for (int i = 0; i < Lanes::kCount; ++i) {
    const ElementInputs& e = elements[std::min(i, count - 1)];  // spare lanes repeat the last element
    const bool inertia = e.mass > 0.0;
    const ElementState<double> one =
        elementState(*e.beam, *e.pose1, *e.pose2, *e.velocity1, *e.velocity2, inertia ? *e.acceleration1 : still,
                     inertia ? *e.acceleration2 : still, gravity);
    for (int j = 0; j < 2; ++j) {
      for (int c = 0; c < 3; ++c) setLane(s.R[j].col[c], i, one.R[j].col[c]);
      setLane(s.spin[j], i, one.spin[j]);
      setLane(s.spinRate[j], i, one.spinRate[j]);
      setLane(s.acceleration[j], i, one.acceleration[j]);
    }
    setLane(s.chord, i, one.chord);
    setLane(s.chordRate, i, one.chordRate);
    setLane(s.chordAcceleration, i, one.chordAcceleration);
    const ElementConstants<double> c = elementConstants(*e.beam, e.damping);
    k.L0.set(i, c.L0);
    k.EA.set(i, c.EA);
    k.damping.set(i, c.damping);
    k.mass.set(i, e.mass);
    for (int j = 0; j < 7; ++j) {
      k.diagonal[j].set(i, c.diagonal[j]);
      k.pair[j].set(i, c.pair[j]);
    }
  }
  ElementForce<Lanes> out;
  if (!elementForce(s, k, out)) return false;
  for (int i = 0; i < count; ++i)
    storeForce(*elements[i].beam,
               {{lane(out.force[0], i), lane(out.force[1], i)}, {lane(out.moment[0], i), lane(out.moment[1], i)}},
               f[i]);
  return true;
}

}  // namespace

// Flattened: every kernel function inlined. The baseline x86-64 variant
// does an operation on four lanes as two SSE2 instructions, the AVX2 one as
// one; AVX2 alone, without FMA: the same operations, rounded alike, so both
// give the same numbers to the bit (a fused multiply-add would not).
[[gnu::flatten]] bool elementForceVectorsBaseline(int count, const ElementInputs elements[], const Vec3& gravity,
                                                  Vec12 f[]) {
  return elementForcesInLanes(count, elements, gravity, f);
}

[[gnu::flatten]] __attribute__((target("avx2"))) bool elementForceVectorsAvx2(int count,
                                                                               const ElementInputs elements[],
                                                                               const Vec3& gravity, Vec12 f[]) {
  return elementForcesInLanes(count, elements, gravity, f);
}

bool hasAvx2() {
  static const bool avx2 = [] {
    __builtin_cpu_init();  // harmless if done; needed if asked before the library's constructors ran
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return avx2;
}

bool elementForceVectors(int count, const ElementInputs elements[], const Vec3& gravity, Vec12 f[]) {
  return hasAvx2() ? elementForceVectorsAvx2(count, elements, gravity, f)
                   : elementForceVectorsBaseline(count, elements, gravity, f);
}

}  // namespace mfbd
