#include "render/gl_api.h"

#include <dlfcn.h>

#include <mutex>
#include <stdexcept>
#include <string>

namespace render {

GlApi gl;
OsMesaApi osmesa;

namespace {

std::string load_error;  // empty once loaded

template <typename F>
void Resolve(void* library, const char* symbol, F* out) {
  void* address = dlsym(library, symbol);
  if (address == nullptr)
    throw std::runtime_error(std::string("render: libOSMesa has no ") + symbol +
                             " (install the Debian package libosmesa6)");
  *out = reinterpret_cast<F>(address);
}

void Load() {
  void* library = nullptr;
  std::string tried;
  for (const char* name : {"libOSMesa.so.8", "libOSMesa.so"}) {
    library = dlopen(name, RTLD_NOW | RTLD_LOCAL);
    if (library != nullptr) break;
    const char* why = dlerror();
    tried += std::string(tried.empty() ? "" : "; ") + (why ? why : name);
  }
  if (library == nullptr)
    throw std::runtime_error(
        "render: cannot load OSMesa (install the Debian package "
        "libosmesa6): " +
        tried);
    // libOSMesa exports the GL entry points itself (FACTS: routing them through libGL breaks them).
#define SCOOPSIM_GL_RESOLVE(name) Resolve(library, "gl" #name, &gl.name);
  SCOOPSIM_GL_FUNCTIONS(SCOOPSIM_GL_RESOLVE)
#undef SCOOPSIM_GL_RESOLVE
#define SCOOPSIM_OSMESA_RESOLVE(name) Resolve(library, "OSMesa" #name, &osmesa.name);
  SCOOPSIM_OSMESA_FUNCTIONS(SCOOPSIM_OSMESA_RESOLVE)
#undef SCOOPSIM_OSMESA_RESOLVE
}

}  // namespace

void LoadGl() {
  static std::once_flag once;
  std::call_once(once, [] {
    try {
      Load();
    } catch (const std::exception& e) {
      load_error = e.what();
    }
  });
  if (!load_error.empty()) throw std::runtime_error(load_error);
}

}  // namespace render
