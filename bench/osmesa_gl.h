/* osmesa_gl.h - the OpenGL 3.3 core entry points the llvmpipe sides of the benches call, looked up
   through OSMesaGetProcAddress (OSMesa exports no prototypes for them). Include after <GL/osmesa.h>
   and <GL/glext.h>; call bench_gl_load(name) once a context is current. One table for every bench
   (C++). */
#ifndef BENCH_OSMESA_GL_H
#define BENCH_OSMESA_GL_H
#include <stdio.h>

#define BENCH_GL_FUNCTIONS(X)                                                                       \
    X(PFNGLCREATESHADERPROC, glCreateShader) X(PFNGLSHADERSOURCEPROC, glShaderSource)               \
    X(PFNGLCOMPILESHADERPROC, glCompileShader) X(PFNGLGETSHADERIVPROC, glGetShaderiv)              \
    X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog) X(PFNGLCREATEPROGRAMPROC, glCreateProgram)    \
    X(PFNGLATTACHSHADERPROC, glAttachShader) X(PFNGLLINKPROGRAMPROC, glLinkProgram)                \
    X(PFNGLGETPROGRAMIVPROC, glGetProgramiv) X(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog)    \
    X(PFNGLUSEPROGRAMPROC, glUseProgram) X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation)      \
    X(PFNGLUNIFORMMATRIX4FVPROC, glUniformMatrix4fv) X(PFNGLUNIFORM3FVPROC, glUniform3fv)          \
    X(PFNGLUNIFORM1FPROC, glUniform1f) X(PFNGLUNIFORM1IPROC, glUniform1i)                          \
    X(PFNGLGENVERTEXARRAYSPROC, glGenVertexArrays) X(PFNGLBINDVERTEXARRAYPROC, glBindVertexArray)  \
    X(PFNGLGENBUFFERSPROC, glGenBuffers) X(PFNGLBINDBUFFERPROC, glBindBuffer)                      \
    X(PFNGLBUFFERDATAPROC, glBufferData) X(PFNGLVERTEXATTRIBPOINTERPROC, glVertexAttribPointer)    \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, glEnableVertexAttribArray)                                 \
    X(PFNGLBINDATTRIBLOCATIONPROC, glBindAttribLocation) X(PFNGLACTIVETEXTUREPROC, glActiveTexture) \
    X(bench_pfn_clear, glClear) X(bench_pfn_clearcolor, glClearColor) X(bench_pfn_enum, glEnable)  \
    X(bench_pfn_enum, glCullFace) X(bench_pfn_enum, glFrontFace) X(bench_pfn_enum, glDepthFunc)    \
    X(bench_pfn_drawelements, glDrawElements) X(bench_pfn_drawarrays, glDrawArrays)                \
    X(bench_pfn_void, glFinish) X(bench_pfn_viewport, glViewport) X(bench_pfn_readpixels, glReadPixels) \
    X(bench_pfn_geterror, glGetError) X(bench_pfn_getstring, glGetString)                          \
    X(bench_pfn_gentextures, glGenTextures) X(bench_pfn_bindtexture, glBindTexture)                \
    X(bench_pfn_teximage2d, glTexImage2D) X(bench_pfn_texparameteri, glTexParameteri)

/* GL 1.x entry points have no PFN...PROC types in glext.h */
typedef void (*bench_pfn_clear)(GLbitfield);
typedef void (*bench_pfn_clearcolor)(GLfloat, GLfloat, GLfloat, GLfloat);
typedef void (*bench_pfn_enum)(GLenum);
typedef void (*bench_pfn_drawelements)(GLenum, GLsizei, GLenum, const void *);
typedef void (*bench_pfn_drawarrays)(GLenum, GLint, GLsizei);
typedef void (*bench_pfn_void)(void);
typedef void (*bench_pfn_viewport)(GLint, GLint, GLsizei, GLsizei);
typedef void (*bench_pfn_readpixels)(GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void *);
typedef GLenum (*bench_pfn_geterror)(void);
typedef const GLubyte *(*bench_pfn_getstring)(GLenum);
typedef void (*bench_pfn_gentextures)(GLsizei, GLuint *);
typedef void (*bench_pfn_bindtexture)(GLenum, GLuint);
typedef void (*bench_pfn_teximage2d)(GLenum, GLint, GLint, GLsizei, GLsizei, GLint, GLenum, GLenum, const void *);
typedef void (*bench_pfn_texparameteri)(GLenum, GLenum, GLint);

#define BENCH_GL_DECLARE(type, name) static type p_##name;
BENCH_GL_FUNCTIONS(BENCH_GL_DECLARE)
#undef BENCH_GL_DECLARE

/* Looks every entry point up; 0 (naming each missing one on stderr, after who) if any is missing. */
static inline int bench_gl_load(const char *who)
{
    int ok = 1;
#define BENCH_GL_LOAD(type, name)                                                  \
    *(void **)(&p_##name) = (void *)OSMesaGetProcAddress(#name);                   \
    if (!p_##name) { fprintf(stderr, "%s: no %s\n", who, #name); ok = 0; }
    BENCH_GL_FUNCTIONS(BENCH_GL_LOAD)
#undef BENCH_GL_LOAD
    return ok;
}
#endif
