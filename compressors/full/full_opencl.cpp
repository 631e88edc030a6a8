#include <vector>

#include "full/full.h"
#include "prtlab/render/btf_table_material.h"

namespace prt::full {

std::unique_ptr<DeviceMaterial> upload_full(ClContext& context,
                                            std::span<const FullMaterial* const> parts) {
  std::vector<const Btf*> btfs;
  for (const FullMaterial* p : parts) btfs.push_back(&p->btf());
  return upload_btf_tables(context, btfs, std::string(kName));
}

}  // namespace prt::full
