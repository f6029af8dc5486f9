#define GL_GLEXT_PROTOTYPES 1
#include "renderer.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace magbake::render {
namespace {

const char* kMeshVs = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 color;
uniform mat4 view_projection;
uniform mat4 model;
out vec3 v_normal;
out vec3 v_color;
void main() {
  v_normal = mat3(model) * normal;
  v_color = color;
  gl_Position = view_projection * model * vec4(position, 1.0);
})";

const char* kMeshFs = R"(#version 330 core
in vec3 v_normal;
in vec3 v_color;
uniform vec3 key_dir;
uniform vec3 fill_dir;
uniform float alpha;
out vec4 frag;
void main() {
  vec3 n = normalize(v_normal);
  float key = max(dot(n, key_dir), 0.0);
  float fill = max(dot(n, fill_dir), 0.0);
  vec3 c = v_color * (0.30 + 0.62 * key + 0.22 * fill);
  frag = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)), alpha);
})";

const char* kLineVs = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 2) in vec3 color;
uniform mat4 view_projection;
out vec3 v_color;
void main() {
  v_color = color;
  gl_Position = view_projection * vec4(position, 1.0);
})";

const char* kLineFs = R"(#version 330 core
in vec3 v_color;
out vec4 frag;
void main() { frag = vec4(pow(clamp(v_color, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0); })";

GLuint compile(GLenum type, const char* src) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    throw std::runtime_error(std::string("preview shader: ") + log);
  }
  return s;
}

GLuint program(const char* vs, const char* fs) {
  const GLuint p = glCreateProgram();
  const GLuint a = compile(GL_VERTEX_SHADER, vs), b = compile(GL_FRAGMENT_SHADER, fs);
  glAttachShader(p, a);
  glAttachShader(p, b);
  glLinkProgram(p);
  glDeleteShader(a);
  glDeleteShader(b);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) throw std::runtime_error("preview shader: link failed");
  return p;
}

// A vertex array with interleaved position, normal, colour (9 floats).
struct Buffer {
  GLuint vao = 0, vbo = 0;
  GLsizei count = 0;
  void upload(const std::vector<float>& data) {
    if (!vao) glGenVertexArrays(1, &vao), glGenBuffers(1, &vbo);
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(), GL_STATIC_DRAW);
    for (GLuint a = 0; a < 3; ++a) {
      glEnableVertexAttribArray(a);
      glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 9 * sizeof(float), reinterpret_cast<void*>(std::size_t(a) * 3 * sizeof(float)));
    }
    count = GLsizei(data.size() / 9);
  }
  void release() {
    if (vao) glDeleteVertexArrays(1, &vao), glDeleteBuffers(1, &vbo);
    vao = vbo = 0;
  }
};

void push(std::vector<float>& d, const Vec3f& p, const Vec3f& n, const Vec3f& c) {
  d.insert(d.end(), {p[0], p[1], p[2], n[0], n[1], n[2], c[0], c[1], c[2]});
}

}  // namespace

Mat4f View::view_projection(int width, int height) const {
  const Eigen::Vector3d f = (target - eye).normalized();
  const Eigen::Vector3d s = f.cross(up).normalized();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d v = Eigen::Matrix4d::Identity();
  v.block<1, 3>(0, 0) = s.transpose();
  v.block<1, 3>(1, 0) = u.transpose();
  v.block<1, 3>(2, 0) = -f.transpose();
  v(0, 3) = -s.dot(eye), v(1, 3) = -u.dot(eye), v(2, 3) = f.dot(eye);
  const double t = 1.0 / std::tan(0.5 * fov), a = double(width) / height;
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = t / a, p(1, 1) = t;
  p(2, 2) = -(far_plane + near_plane) / (far_plane - near_plane);
  p(2, 3) = -2.0 * far_plane * near_plane / (far_plane - near_plane);
  p(3, 2) = -1;
  return (p * v).cast<float>();
}

struct Renderer::Gl {
  GLuint mesh_program = 0, line_program = 0;
  std::vector<Buffer> meshes;
  std::vector<int> mesh_body;
  std::vector<float> mesh_alpha;
  Buffer ground, lines;
};

Renderer::Renderer(GlContext& context) : context_(context), gl_(new Gl) {
  gl_->mesh_program = program(kMeshVs, kMeshFs);
  gl_->line_program = program(kLineVs, kLineFs);
  glEnable(GL_DEPTH_TEST);
  glViewport(0, 0, context_.width(), context_.height());
}

Renderer::~Renderer() {
  for (auto& b : gl_->meshes) b.release();
  gl_->ground.release();
  gl_->lines.release();
  glDeleteProgram(gl_->mesh_program);
  glDeleteProgram(gl_->line_program);
  delete gl_;
}

void Renderer::set_meshes(const std::vector<Mesh>& meshes) {
  for (auto& b : gl_->meshes) b.release();
  gl_->meshes.clear();
  gl_->mesh_body.clear();
  gl_->mesh_alpha.clear();
  for (const Mesh& m : meshes) {
    std::vector<float> d;
    d.reserve(m.positions.size() * 9);
    for (std::size_t i = 0; i + 2 < m.positions.size(); i += 3) {
      // Flat shading: the face normal on each of the triangle's vertices.
      const Vec3f n = (m.positions[i + 1] - m.positions[i]).cross(m.positions[i + 2] - m.positions[i]).normalized();
      for (int k = 0; k < 3; ++k) push(d, m.positions[i + k], n, m.colors[i + k]);
    }
    Buffer b;
    b.upload(d);
    gl_->meshes.push_back(b);
    gl_->mesh_body.push_back(m.body);
    gl_->mesh_alpha.push_back(m.alpha);
  }
}

void Renderer::set_ground(double cx, double cy, double z, double extent, double spacing) {
  std::vector<float> d;
  const Vec3f n(0, 0, 1);
  const int k = static_cast<int>(std::ceil(extent / spacing));
  for (int i = -k; i <= k; ++i) {
    const float c = (i % 5 == 0) ? 0.62f : 0.78f;  // every fifth line darker
    const float a = float(i * spacing);
    push(d, Vec3f(cx + a, cy - k * spacing, z), n, Vec3f(c, c, c));
    push(d, Vec3f(cx + a, cy + k * spacing, z), n, Vec3f(c, c, c));
    push(d, Vec3f(cx - k * spacing, cy + a, z), n, Vec3f(c, c, c));
    push(d, Vec3f(cx + k * spacing, cy + a, z), n, Vec3f(c, c, c));
  }
  gl_->ground.upload(d);
}

std::vector<std::uint8_t> Renderer::draw(const View& view, const std::vector<Mat4f>& transforms,
                                         const std::vector<Polyline>& lines) {
  const Vec3f bg = background();
  glClearColor(bg[0], bg[1], bg[2], 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  const Mat4f vp = view.view_projection(context_.width(), context_.height());
  // Lights fixed to the camera: key from the upper left, fill from the right.
  const Eigen::Vector3d f = (view.target - view.eye).normalized();
  const Eigen::Vector3d s = f.cross(view.up).normalized(), u = s.cross(f);
  const Vec3f key = (-f + 0.8 * u - 0.6 * s).normalized().cast<float>();
  const Vec3f fill = (-f + 0.9 * s - 0.2 * u).normalized().cast<float>();
  glUseProgram(gl_->mesh_program);
  glUniformMatrix4fv(glGetUniformLocation(gl_->mesh_program, "view_projection"), 1, GL_FALSE, vp.data());
  glUniform3fv(glGetUniformLocation(gl_->mesh_program, "key_dir"), 1, key.data());
  glUniform3fv(glGetUniformLocation(gl_->mesh_program, "fill_dir"), 1, fill.data());
  const GLint model = glGetUniformLocation(gl_->mesh_program, "model");
  const GLint alpha = glGetUniformLocation(gl_->mesh_program, "alpha");
  // Opaque meshes first, then translucent casings blended over them without writing depth.
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) glEnable(GL_BLEND), glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA), glDepthMask(GL_FALSE);
    for (std::size_t i = 0; i < gl_->meshes.size(); ++i) {
      if ((gl_->mesh_alpha[i] < 1.0f) != (pass == 1)) continue;
      const Mat4f& m = transforms.at(gl_->mesh_body[i]);
      glUniformMatrix4fv(model, 1, GL_FALSE, m.data());
      glUniform1f(alpha, gl_->mesh_alpha[i]);
      glBindVertexArray(gl_->meshes[i].vao);
      glDrawArrays(GL_TRIANGLES, 0, gl_->meshes[i].count);
    }
  }
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
  // Ground grid and field lines: unlit lines.
  glUseProgram(gl_->line_program);
  glUniformMatrix4fv(glGetUniformLocation(gl_->line_program, "view_projection"), 1, GL_FALSE, vp.data());
  if (gl_->ground.count) {
    glBindVertexArray(gl_->ground.vao);
    glDrawArrays(GL_LINES, 0, gl_->ground.count);
  }
  if (!lines.empty()) {
    std::vector<float> d;
    std::vector<GLint> first;
    std::vector<GLsizei> count;
    for (const Polyline& l : lines) {
      first.push_back(GLint(d.size() / 9));
      count.push_back(GLsizei(l.points.size()));
      for (std::size_t k = 0; k < l.points.size(); ++k) push(d, l.points[k], Vec3f::UnitZ(), l.colors[k]);
    }
    gl_->lines.upload(d);
    glBindVertexArray(gl_->lines.vao);
    // Field lines about 2 px wide at 720p, scaled with the image (clamped to what the driver allows).
    GLfloat range[2] = {1, 1};
    glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, range);
    glLineWidth(std::clamp(context_.height() / 360.0f, 1.0f, range[1]));
    glMultiDrawArrays(GL_LINE_STRIP, first.data(), count.data(), GLsizei(first.size()));
    glLineWidth(1.0f);
  }
  return context_.read_rgba();
}

}  // namespace magbake::render
