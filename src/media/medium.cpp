#include "media/medium.h"

namespace ferry {

size_t Medium::bytes() const {
  size_t b = sizeof(Medium);
  if (density) b += density->bytes();
  if (majorants)
    b += size_t(majorants->cells(0)) * size_t(majorants->cells(1)) * size_t(majorants->cells(2)) *
         sizeof(float);
  return b;
}

Medium gridMedium(std::string name, Vec3f sigmaA, Vec3f sigmaS, float g,
                  std::shared_ptr<const DensityGrid> density, const Affine3f& worldFromMedium,
                  const Box3f& box) {
  Medium m;
  m.name = std::move(name);
  m.sigmaA = sigmaA;
  m.sigmaS = sigmaS;
  m.g = g;
  m.majorants = std::make_shared<MajorantGrid>(*density);
  m.density = std::move(density);
  const Vec3f size = box.size();
  const Affine3f unitFromBox = Affine3f::scale({1 / size.x, 1 / size.y, 1 / size.z}) *
                               Affine3f::translate(-box.lower);
  m.gridFromWorld = unitFromBox * worldFromMedium.inverse();
  return m;
}

}  // namespace ferry
