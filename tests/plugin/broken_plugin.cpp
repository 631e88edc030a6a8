// Two shared libraries that prt::load_plugin() must refuse (tests/plugin/plugin_load_test.cpp):
//   PRTLAB_BROKEN_PLUGIN_WRONG_API  both entry points, but built for another plugin API version:
//                                   the situation of a plugin compiled against an older prtlab
//   (otherwise)                     a shared library that is not a prtlab plugin at all
// Neither may ever have its registration function called.
#include <cstdlib>

#include "prtlab/compress/compressor_registry.h"

#ifdef PRTLAB_BROKEN_PLUGIN_WRONG_API
extern "C" int prtlab_plugin_api_version() {
  return prt::kPluginApiVersion + 1;
}
extern "C" void prtlab_register_plugin(prt::CompressorRegistry&) {
  std::abort();  // prtlab must refuse the plugin before this point
}
#else
extern "C" int prtlab_unrelated_function() {
  return 0;
}
#endif
