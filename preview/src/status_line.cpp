#include "status_line.hpp"

#include "renderer.hpp"

#include "meso/preview/preview.hpp"

#include <stb/stb_easy_font.h>

#include <algorithm>
#include <cstdio>
#include <vector>

namespace meso {

namespace {

// Pixel positions (origin top left, y down) to clip space; one flat colour.
const char* const kVertex = R"(#version 450 core
layout(location = 0) in vec2 a_pixel;
uniform vec2 u_viewport;
uniform float u_scale;
void main() {
  vec2 p = a_pixel * u_scale;
  gl_Position = vec4(2.0 * p.x / u_viewport.x - 1.0, 1.0 - 2.0 * p.y / u_viewport.y, 0.0, 1.0);
}
)";
const char* const kFragment = R"(#version 450 core
uniform vec4 u_color;
layout(location = 0) out vec4 out_color;
void main() { out_color = u_color; }
)";

// Two triangles per quad of stb_easy_font's output (x, y, z float and 4 colour bytes per
// corner, corners in order around the quad).
void append_quads(const std::vector<unsigned char>& buffer, int quads, std::vector<float>& out) {
  for (int q = 0; q < quads; ++q) {
    float corner[4][2];
    for (int k = 0; k < 4; ++k) {
      const unsigned char* v = buffer.data() + (static_cast<size_t>(q) * 4 + static_cast<size_t>(k)) * 16;
      std::copy_n(reinterpret_cast<const float*>(v), 2, corner[k]);
    }
    for (int k : {0, 1, 2, 0, 2, 3}) out.insert(out.end(), {corner[k][0], corner[k][1]});
  }
}

}  // namespace

StatusLine::StatusLine() {
  program_ = link({compile(GL_VERTEX_SHADER, {kVertex}), compile(GL_FRAGMENT_SHADER, {kFragment})});
  glCreateVertexArrays(1, &vao_);
  glCreateBuffers(1, &vbo_);
  glVertexArrayVertexBuffer(vao_, 0, vbo_, 0, 2 * sizeof(float));
  glEnableVertexArrayAttrib(vao_, 0);
  glVertexArrayAttribFormat(vao_, 0, 2, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(vao_, 0, 0);
}

StatusLine::~StatusLine() {
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void StatusLine::draw(const std::string& text, int width, int height) {
  if (text.empty() || width <= 0 || height <= 0) return;
  std::string line(text);
  std::replace_if(line.begin(), line.end(), [](char c) { return c < 32 || c > 126; }, '?');  // one line, ASCII
  // stb_easy_font: about 270 bytes of vertices per character; the text at (3, 3) stroke units.
  std::vector<unsigned char> buffer(line.size() * 300 + 300);
  const int quads = stb_easy_font_print(3.0f, 3.0f, line.data(), nullptr, buffer.data(), static_cast<int>(buffer.size()));
  std::vector<float> text_triangles;
  append_quads(buffer, quads, text_triangles);
  const float band_w = static_cast<float>(stb_easy_font_width(line.data()) + 6), band_h = static_cast<float>(stb_easy_font_height(line.data()) + 4);
  const std::vector<float> band = {0, 0, band_w, 0, band_w, band_h, 0, 0, band_w, band_h, 0, band_h};
  const float scale = static_cast<float>(std::max(1, height / 480));

  glUseProgram(program_);
  glUniform2f(glGetUniformLocation(program_, "u_viewport"), static_cast<float>(width), static_cast<float>(height));
  glUniform1f(glGetUniformLocation(program_, "u_scale"), scale);
  GLboolean depth_test = GL_FALSE, blend = GL_FALSE;
  glGetBooleanv(GL_DEPTH_TEST, &depth_test);
  glGetBooleanv(GL_BLEND, &blend);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  // The band darkens what is under it; its alpha raises coverage to at least 0.6.
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);  // the fetch attachment, headless
  glBindVertexArray(vao_);
  auto triangles = [&](const std::vector<float>& xy, float r, float g, float b, float a) {
    glNamedBufferData(vbo_, static_cast<GLsizeiptr>(xy.size() * sizeof(float)), xy.data(), GL_STREAM_DRAW);
    glUniform4f(glGetUniformLocation(program_, "u_color"), r, g, b, a);
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(xy.size() / 2));
  };
  triangles(band, 0.0f, 0.0f, 0.0f, 0.6f);
  triangles(text_triangles, 1.0f, 1.0f, 1.0f, 1.0f);
  glBindVertexArray(0);
  glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  if (!blend) glDisable(GL_BLEND);
  if (depth_test) glEnable(GL_DEPTH_TEST);
}

std::string preview_status_line(const PreviewOptions& o, double ms) {
  static const char* const shadow_names[3] = {"no shadows", "hard shadows", "soft shadows"};
  char knobs[160] = "";
  if (o.method == "relief") std::snprintf(knobs, sizeof knobs, " | %d halvings", o.binary_steps);
  else if (o.method == "relaxed-cone") std::snprintf(knobs, sizeof knobs, " | %d bisections", o.bisection_steps);
  else if (o.method == "dig")
    std::snprintf(knobs, sizeof knobs, " | epsilon %.3g | fallback %.3g texels", static_cast<double>(o.dig_epsilon),
                  static_cast<double>(o.dig_fallback_texels));
  else if (o.method == "tessellation")
    std::snprintf(knobs, sizeof knobs, " | edge tests %.3g of range, %.3g deg, %.3g px, %d samples", static_cast<double>(o.tess_displacement),
                  static_cast<double>(o.tess_normal_angle), static_cast<double>(o.tess_pixels), o.tess_edge_samples);
  char line[512];
  std::snprintf(line, sizeof line, "%s | %d iterations%s | view %.1f deg | %s%s | %.2f ms", o.method.c_str(), o.iterations, knobs,
                static_cast<double>(o.camera.view_angle), shadow_names[static_cast<int>(o.shadows) % 3], o.silhouettes ? " | silhouettes" : "", ms);
  return line;
}

}  // namespace meso
