#pragma once
// Shader programs of mbi::gpu and the viewer: one compile-and-link helper, and the GLSL sources,
// each a file of gpu/gl/shaders/ embedded at configure time (GLSL 3.30 core).
#include <mbi/gpu/context.hpp>

#include <string>
#include <vector>

namespace mbi::gpu {

/// A program's two stages, GLSL without the "#version" line; `fragment` null for a
/// transform-feedback pass.
struct ShaderSource {
  const char* vertex = nullptr;
  const char* fragment = nullptr;
};

namespace shaders {
/// The dense surface under a headlight (uniforms view_projection, eye_direction, color; with
/// "#define VERTEX_COLOR" a colour per vertex at location 3 instead of the uniform).
extern const ShaderSource mesh;
/// 2D: the warped picture (uniforms view_projection, origin, image_size, image).
extern const ShaderSource texture;
/// Lines and points in a flat colour (uniforms view_projection, color).
extern const ShaderSource line;
/// The viewer's clay material (uniforms view_projection, view_rotation, color).
extern const ShaderSource material;
/// The viewer's ground with grid and shadow (see ground.vert and ground.frag for the uniforms).
extern const ShaderSource ground;
}  // namespace shaders

/// Compiles and links a program from "#version 330 core\n" + `defines` + each stage; transform
/// feedback outputs (if any) are set before linking. Needs a current context. Throws Error
/// "OpenGL: <what>: shader does not compile: <log>" (or "program does not link").
unsigned program(const char* what, const ShaderSource& source, const std::string& defines = "",
                 const std::vector<const char*>& feedback = {});

}  // namespace mbi::gpu
