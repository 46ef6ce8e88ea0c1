// The OSMesa and GL entry points the renderer calls, looked up at run time. libOSMesa pulls in
// libLLVM (llvmpipe), whose load-time relocations alone add about 50 MB of resident memory: linking
// it would charge that to every run, rendering or not. It is opened with dlopen the first time a
// Renderer is made instead.
#pragma once

#define GL_GLEXT_PROTOTYPES 1  // prototypes for decltype only: nothing here links against GL
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

namespace render {

#define SCOOPSIM_GL_FUNCTIONS(X)                                                                   \
  X(AttachShader)                                                                                  \
  X(BindBuffer) X(BindVertexArray) X(BufferData) X(BufferSubData) X(Clear) X(ClearColor)           \
      X(ClearDepth) X(CompileShader) X(CreateProgram) X(CreateShader) X(DeleteShader) X(DepthFunc) \
          X(DrawArrays) X(Enable) X(EnableVertexAttribArray) X(Finish) X(GenBuffers)               \
              X(GenVertexArrays) X(GetError) X(GetProgramInfoLog) X(GetProgramiv)                  \
                  X(GetShaderInfoLog) X(GetShaderiv) X(GetString) X(GetUniformLocation)            \
                      X(LinkProgram) X(ShaderSource) X(Uniform1f) X(Uniform1i) X(Uniform2f)        \
                          X(Uniform3f) X(Uniform3fv) X(UniformMatrix4fv) X(UseProgram)             \
                              X(VertexAttribPointer) X(Viewport)

#define SCOOPSIM_OSMESA_FUNCTIONS(X) X(CreateContextAttribs) X(MakeCurrent) X(DestroyContext)

// gl.Clear(...) calls glClear, osmesa.MakeCurrent(...) calls OSMesaMakeCurrent.
struct GlApi {
#define SCOOPSIM_GL_MEMBER(name) decltype(&::gl##name) name = nullptr;
  SCOOPSIM_GL_FUNCTIONS(SCOOPSIM_GL_MEMBER)
#undef SCOOPSIM_GL_MEMBER
};
struct OsMesaApi {
#define SCOOPSIM_OSMESA_MEMBER(name) decltype(&::OSMesa##name) name = nullptr;
  SCOOPSIM_OSMESA_FUNCTIONS(SCOOPSIM_OSMESA_MEMBER)
#undef SCOOPSIM_OSMESA_MEMBER
};

// Opens libOSMesa once (thread-safe) and resolves every entry point above. Throws
// std::runtime_error naming the library or the missing symbol and the package to install.
void LoadGl();
extern GlApi gl;
extern OsMesaApi osmesa;

}  // namespace render
