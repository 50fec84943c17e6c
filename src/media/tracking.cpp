#include "media/tracking.h"

#include <algorithm>
#include <cmath>

namespace ferry {
namespace {

// Transmittance paths below this take Russian roulette (survive half the time, doubled).
constexpr float kRouletteTransmittance = 0.005f;
// Residual ratio tracking steps against this times the residual's bound: a
// ratio-tracking estimate's relative variance is exp(integral of r^2 / rate)
// - 1 for a residual r, so a higher rate costs more steps but fewer
// estimates for an error (docs/volumes.md, "Shadow rays", measures it).
constexpr float kResidualMajorantScale = 8;

// A distance with density rate x exp(-rate x), from u in [0, 1) (1 - u > 0;
// logf, not log1pf: a third of ratio tracking's time went to log1pf).
float exponential(float u, float rate) {
  return -std::log(1 - u) / rate;
}

Vec3f homogeneousTransmittance(const Medium& m, float length) {
  const Vec3f s = m.sigmaT();
  Vec3f t;
  for (int c = 0; c < 3; ++c) t[c] = s[c] > 0 ? std::exp(-s[c] * length) : 1.0f;
  return t;
}

// The radiance a homogeneous medium emits towards the origin along `length`:
// the integral of T(t) sigma_a Le.
Vec3f homogeneousEmission(const Medium& m, float length) {
  const Vec3f s = m.sigmaT();
  Vec3f e;
  for (int c = 0; c < 3; ++c) {
    if (!(s[c] > 0) || !(m.sigmaA[c] > 0)) {
      e[c] = 0;
      continue;
    }
    const float fraction = std::isfinite(length) ? -std::expm1(-s[c] * length) : 1.0f;
    e[c] = m.sigmaA[c] * m.emission[c] * fraction / s[c];
  }
  return e;
}

FreeFlight homogeneousFlight(const Medium& m, float tMin, float tMax, TrackingRandom& random,
                             MediumCounts& counts) {
  FreeFlight f;
  if (m.emits()) f.emitted = homogeneousEmission(m, tMax - tMin);
  const Vec3f sigmaT = m.sigmaT();
  const int channel = std::min(int(random.next() * 3), 2);
  const float u = random.next();
  const float distance = sigmaT[channel] > 0 ? exponential(u, sigmaT[channel]) : kInfinity;
  const bool scattered = distance < tMax - tMin;
  const float length = scattered ? distance : tMax - tMin;
  const Vec3f tr = homogeneousTransmittance(m, length);
  const Vec3f density = scattered ? sigmaT * tr : tr;
  const float pdf = (density.x + density.y + density.z) / 3;
  if (!(pdf > 0)) {
    f.weight = Vec3f(0);
    return f;
  }
  if (scattered) {
    ++counts.realCollisions;
    f.event = FreeFlight::Event::Scattered;
    f.t = tMin + distance;
    f.weight = tr * m.sigmaS * (1 / pdf);
  } else {
    f.weight = tr * (1 / pdf);
  }
  return f;
}

}  // namespace

FreeFlight sampleFreeFlight(const Medium& m, Vec3f o, Vec3f d, float tMin, float tMax,
                            TrackingRandom& random, MediumCounts& counts) {
  if (m.homogeneous()) return homogeneousFlight(m, tMin, tMax, random, counts);
  FreeFlight f;
  const Vec3f og = m.gridFromWorld.transformPoint(o), dg = m.gridFromWorld.transformVector(d);
  float t0 = tMin, t1 = tMax;
  if (!clipToUnitCube(og, dg, t0, t1)) return f;
  m.majorants->walk(og, dg, t0, t1, [&](float a, float b, float majorant, const Vec3f&) {
    ++counts.majorantCells;
    if (!(majorant > 0)) return true;
    for (float t = a;;) {
      t += exponential(random.next(), majorant);
      if (!(t < b)) return true;
      Vec3f sa, ss;
      m.coefficients(og + dg * t, sa, ss);
      const Vec3f sn = max(Vec3f(majorant) - sa - ss, Vec3f(0));
      // Spectral tracking: each event chosen by its largest channel, each
      // channel weighed by its coefficient over the event's probability.
      const float pa = maxComponent(sa), ps = maxComponent(ss), pn = maxComponent(sn);
      const float sum = pa + ps + pn;
      const float u = random.next() * sum;
      if (u < pa || (pn <= 0 && ps <= 0)) {
        if (!(pa > 0)) return true;
        ++counts.realCollisions;
        f.weight = f.weight * sa * (sum / (majorant * pa));
        if (m.emits()) f.emitted = f.weight * m.emittedAt(og + dg * t);
        f.event = FreeFlight::Event::Absorbed;
        f.t = t;
        return false;
      }
      if (u < pa + ps || pn <= 0) {
        ++counts.realCollisions;
        f.weight = f.weight * ss * (sum / (majorant * ps));
        f.event = FreeFlight::Event::Scattered;
        f.t = t;
        return false;
      }
      ++counts.nullCollisions;
      f.weight = f.weight * sn * (sum / (majorant * pn));
    }
  });
  return f;
}

Vec3f transmittance(const Medium& m, Vec3f o, Vec3f d, float tMin, float tMax,
                    TransmittanceEstimator estimator, TrackingRandom& random,
                    MediumCounts& counts) {
  if (m.homogeneous()) return homogeneousTransmittance(m, tMax - tMin);
  Vec3f tr{1, 1, 1};
  const Vec3f og = m.gridFromWorld.transformPoint(o), dg = m.gridFromWorld.transformVector(d);
  float t0 = tMin, t1 = tMax;
  if (!clipToUnitCube(og, dg, t0, t1)) return tr;
  m.majorants->walk(og, dg, t0, t1, [&](float a, float b, float majorant, const Vec3f& control) {
    ++counts.majorantCells;
    if (!(majorant > 0)) return true;
    auto sigmaTAt = [&](float t) {
      Vec3f sa, ss;
      m.coefficients(og + dg * t, sa, ss);
      return sa + ss;
    };
    if (estimator == TransmittanceEstimator::Ratio) {
      // Residual ratio tracking (Novak et al. 2014): the cell's control (its
      // mean extinction) in closed form, the rest by ratio tracking at a
      // rate above the residual's largest (so weights stay >= 0; where the
      // extinction is below the control they exceed 1).
      if (maxComponent(control) > 0) {
        const Vec3f depth = control * (b - a);
        tr = tr * Vec3f(std::exp(-depth.x), std::exp(-depth.y), std::exp(-depth.z));
      }
      const float residual =
          (majorant - std::min({control.x, control.y, control.z})) * kResidualMajorantScale;
      if (!(residual > 0)) return maxComponent(tr) > 0;
      for (float t = a;;) {
        t += exponential(random.next(), residual);
        if (!(t < b)) return true;
        ++counts.nullCollisions;
        tr = tr * max(Vec3f(1) - (sigmaTAt(t) - control) * (1 / residual), Vec3f(0));
        if (maxComponent(tr) < kRouletteTransmittance) {
          if (random.next() < 0.5f) {
            tr = Vec3f(0);
            return false;
          }
          tr = tr * 2.0f;
        }
      }
    }
    for (float t = a;;) {
      t += exponential(random.next(), majorant);
      if (!(t < b)) return true;
      const Vec3f nullFraction = max(Vec3f(1) - sigmaTAt(t) * (1 / majorant), Vec3f(0));
      // Delta tracking: a real collision (with the channels' mean
      // probability) ends it; each channel is weighed by its own null
      // fraction over the mean's (for a grey medium, 0 or 1).
      const float real = 1 - (nullFraction.x + nullFraction.y + nullFraction.z) / 3;
      if (random.next() < real) {
        ++counts.realCollisions;
        tr = Vec3f(0);
        return false;
      }
      ++counts.nullCollisions;
      tr = tr * nullFraction * (1 / (1 - real));
    }
  });
  return tr;
}

}  // namespace ferry
