#include "tridex/backends/backends.hpp"

#include <string>

#include "tridex/backends/embree_dexelize.hpp"
#include "tridex/backends/gl_mill.hpp"
#include "tridex/error.hpp"
#include "tridex/intersect_milled.hpp"
#include "tridex/scan_dexelize.hpp"

namespace tridex::backends {

const char* to_string(ZMapBackend backend) {
  switch (backend) {
    case ZMapBackend::cpu:
      return "cpu";
    case ZMapBackend::gl:
      return "gl";
  }
  return "?";
}

const char* to_string(DexelBackend backend) {
  switch (backend) {
    case DexelBackend::tree:
      return "tree";
    case DexelBackend::embree:
      return "embree";
    case DexelBackend::scan:
      return "scan";
  }
  return "?";
}

ZMapBackend parse_zmap_backend(std::string_view name) {
  for (ZMapBackend b : {ZMapBackend::cpu, ZMapBackend::gl})
    if (name == to_string(b)) return b;
  detail::fail("unknown Z-map backend '", std::string(name), "' (valid: cpu, gl)");
}

DexelBackend parse_dexel_backend(std::string_view name) {
  for (DexelBackend b : {DexelBackend::tree, DexelBackend::embree, DexelBackend::scan})
    if (name == to_string(b)) return b;
  detail::fail("unknown dexel backend '", std::string(name), "' (valid: tree, embree, scan)");
}

bool available(ZMapBackend backend) { return backend == ZMapBackend::cpu || gl_available(); }

bool available(DexelBackend) { return true; }

void mill_with(ZMapBackend backend, ZMap& map, std::span<const Cutter> cutters,
               std::span<const CutMove> moves, unsigned threads) {
  switch (backend) {
    case ZMapBackend::cpu:
      mill(map, cutters, moves, {.threads = threads});
      return;
    case ZMapBackend::gl:
      gl_mill(map, cutters, moves);
      return;
  }
  detail::fail("mill_with: invalid Z-map backend ", static_cast<int>(backend));
}

TripleDexel machine_with(DexelBackend backend, const TripleDexel& stock,
                         std::span<const ZMap> milled, unsigned threads) {
  switch (backend) {
    case DexelBackend::tree:
      return intersect_milled(stock, milled, threads);
    case DexelBackend::embree:
      return embree_machine(stock, milled, threads);
    case DexelBackend::scan:
      return scan_intersect_milled(stock, milled, threads);
  }
  detail::fail("machine_with: invalid dexel backend ", static_cast<int>(backend));
}

}  // namespace tridex::backends
