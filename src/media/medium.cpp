#include "media/medium.h"

namespace ferry {

size_t Medium::bytes() const {
  size_t b = sizeof(Medium);
  if (density) b += density->bytes();
  if (majorants)
    b += size_t(majorants->cells(0)) * size_t(majorants->cells(1)) * size_t(majorants->cells(2)) *
         (sizeof(float) + sizeof(Vec3f));
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
  const Vec3f sigmaT = sigmaA + sigmaS;
  m.majorants = std::make_shared<MajorantGrid>(*density, [sigmaT](float lo, float hi) {
    return std::pair{hi * maxComponent(sigmaT), sigmaT * lo};
  });
  m.density = std::move(density);
  const Vec3f size = box.size();
  const Affine3f unitFromBox =
      Affine3f::scale({1 / size.x, 1 / size.y, 1 / size.z}) * Affine3f::translate(-box.lower);
  m.gridFromWorld = unitFromBox * worldFromMedium.inverse();
  return m;
}

Medium transferFunctionMedium(std::string name, std::shared_ptr<const DensityGrid> values,
                              std::shared_ptr<const TransferFunction> transfer, const Box3f& box) {
  Medium m;
  m.name = std::move(name);
  m.density = std::move(values);
  const Vec3f size = box.size();
  m.gridFromWorld =
      Affine3f::scale({1 / size.x, 1 / size.y, 1 / size.z}) * Affine3f::translate(-box.lower);
  setTransferFunction(m, std::move(transfer));
  return m;
}

void setTransferFunction(Medium& m, std::shared_ptr<const TransferFunction> transfer) {
  const TransferFunction& tf = *transfer;
  m.majorants = std::make_shared<MajorantGrid>(*m.density, [&tf](float lo, float hi) {
    const auto [smallest, largest] = tf.opacityRange(lo, hi);
    return std::pair{largest * tf.scale(), Vec3f(smallest * tf.scale())};
  });
  m.transfer = std::move(transfer);
}

}  // namespace ferry
