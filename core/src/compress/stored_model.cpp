#include "prtlab/compress/stored_model.h"

namespace prt {

// Out of line: the vtable and type information live in libprtlab_core, so that stored_model()
// finds the interface in any backend, built in or a plugin.
StoredModel::~StoredModel() = default;

const StoredModel* stored_model(const CompressedTransfer& ct) {
  return dynamic_cast<const StoredModel*>(&ct);
}

}  // namespace prt
