// Anchor of the prtlab_experiments library (each experiment lives in its own file here).
namespace prt::experiments {}
