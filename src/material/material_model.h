// A material model: how a surface scatters light, with its parameters. The
// scene's materials (scene/scene.h) each hold one, beside what every surface
// has (colour and its texture, emission, cut-out, bump, mix). A model makes
// the Bsdf at a shading point and writes itself to a part-file record; the
// registry (material_models.cpp) names every model, so a part file is read
// back by the model's name. Adding a model: docs/architecture.md.
#pragma once

#include <cstdint>
#include <cstring>
#include <deque>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/math.h"
#include "core/record.h"
#include "material/bsdf.h"
#include "material/fourier_bsdf_table.h"

namespace ferry {

constexpr int32_t kNoBsdfTable = -1;

// What a model may read besides its parameters when it makes a Bsdf.
struct MaterialResources {
  // The scene's tabulated BSDFs (Scene::bsdfTables).
  std::span<const std::shared_ptr<const FourierBsdfTable>> bsdfTables;
};

// A model's parameters as bytes, in a part file (core/record.h). The part
// file renumbers the tables a model names (it keeps only the ones its
// materials use): a model writes a table index through table(), and reads it
// back through table(), which checks it against the tables there are.
class MaterialRecordWriter : public RecordWriter {
 public:
  using TableIndex = std::function<int32_t(int32_t)>;
  explicit MaterialRecordWriter(TableIndex tableIndex = {}) : tableIndex_(std::move(tableIndex)) {}
  void table(int32_t index) { pod(tableIndex_ ? tableIndex_(index) : index); }

 private:
  TableIndex tableIndex_;
};

class MaterialRecordReader : public RecordReader {
 public:
  MaterialRecordReader(std::span<const uint8_t> bytes, std::string where, size_t bsdfTables)
      : RecordReader(bytes, std::move(where)), tables_(bsdfTables) {}
  int32_t table();

 private:
  size_t tables_;
};

class MaterialModel {
 public:
  virtual ~MaterialModel() = default;
  // The name it is registered and written under (material_models.cpp).
  virtual std::string_view name() const = 0;
  // The Bsdf at a shading point whose colour (the material's base colour
  // times its texture there) is `color`.
  virtual Bsdf bsdf(Vec3f color, const MaterialResources& resources) const = 0;
  // The same at surface coordinates `uv` (the hit's: a fibre's v runs across
  // it), for models that read where on the surface they are.
  virtual Bsdf bsdfAt(Vec3f color, Vec2f /*uv*/, const MaterialResources& resources) const {
    return bsdf(color, resources);
  }
  // The tabulated BSDF it reads (MaterialResources::bsdfTables), if any.
  virtual int32_t bsdfTable() const { return kNoBsdfTable; }
  virtual void write(MaterialRecordWriter& record) const = 0;
  // A line for people: the model and its parameters.
  virtual std::string describe() const = 0;
};

// A registered model: its name, a line of help and how it reads a record.
struct MaterialModelKind {
  std::string name;
  std::string summary;
  std::function<std::shared_ptr<const MaterialModel>(MaterialRecordReader&)> read;
};

// Every model, the built-in ones first (material_models.cpp).
const std::deque<MaterialModelKind>& materialModelKinds();
// Null if none has that name.
const MaterialModelKind* materialModelKind(std::string_view name);
// Adds a model (a test's, an application's); a name already taken is an InternalError.
void registerMaterialModel(MaterialModelKind kind);
// Every model's name, "a, b, c".
std::string materialModelNames();

// `model` with each BSDF table index t it names replaced by newIndex(t) (by
// writing its record and reading it back); `model` itself if it names none.
std::shared_ptr<const MaterialModel> withBsdfTablesRenumbered(
    const std::shared_ptr<const MaterialModel>& model,
    const MaterialRecordWriter::TableIndex& newIndex);

// The model a Material starts with: Lambertian.
std::shared_ptr<const MaterialModel> defaultMaterialModel();

}  // namespace ferry
