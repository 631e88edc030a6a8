// The OBJECT library of built-in backends. Backends live in compressors/<name>/ and register
// themselves with PRT_REGISTER_COMPRESSOR; this file only gives the library a translation unit
// of its own so that it exists while no backend folder does.
namespace prt::compressors {
int builtin_compressor_library_anchor() {
  return 0;
}
}  // namespace prt::compressors
