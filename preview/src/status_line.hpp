// The previewer's on-screen line (internal): one line of text drawn over the frame at its
// top left, on a dark band, with stb_easy_font's vector glyphs (ASCII 32-126; no font file).
// Needs a current OpenGL 4.5 core context.
#pragma once

#include <epoxy/gl.h>

#include <string>

namespace meso {

class StatusLine {
 public:
  StatusLine();
  ~StatusLine();
  StatusLine(const StatusLine&) = delete;
  StatusLine& operator=(const StatusLine&) = delete;

  // Draws `text` into the bound framebuffer (width x height pixels) over what is there, in
  // draw buffer 0 only (the headless fetch attachment keeps its values), depth test off.
  // Glyphs are 1 pixel per stroke unit up to 480 pixels of height, then scaled by height / 480
  // rounded down. Colour: white text, alpha 1, on a black band of alpha 0.6.
  void draw(const std::string& text, int width, int height);

 private:
  GLuint program_ = 0, vao_ = 0, vbo_ = 0;
};

}  // namespace meso
