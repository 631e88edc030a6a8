// Two shared libraries that prt::load_plugin() must refuse (tests/plugin/plugin_load_test.cpp):
//   PRTLAB_BROKEN_PLUGIN_WRONG_API  registers with the macro every backend uses, but built for
//                                   another plugin API version: the situation of a plugin
//                                   compiled against an older prtlab
//   (otherwise)                     a shared library that is not a prtlab plugin at all
// Neither may ever have its entry function called.
#include <cstdlib>

#include "prtlab/compress/compressor_registry.h"

#ifdef PRTLAB_BROKEN_PLUGIN_WRONG_API
namespace {
prt::CompressorEntry never_called() {
  std::abort();  // prtlab must refuse the plugin before this point
}
// PRT_REGISTER_COMPRESSOR, with the API version a plugin for the next prtlab would carry.
const prt::CompressorRegistrar registrar{&never_called, prt::kPluginApiVersion + 1};
}  // namespace
#else
extern "C" int prtlab_unrelated_function() {
  return 0;
}
#endif
