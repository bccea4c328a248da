#include "build/param_overrides.h"

#include <charconv>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <type_traits>

namespace kg {
namespace {

template <class T>
bool parse_number(const std::string& text, T& out) {
  if constexpr (std::is_floating_point_v<T>) {
    try {
      std::size_t used = 0;
      const double v = std::stod(text, &used);
      if (used != text.size()) return false;
      out = static_cast<T>(v);
      return true;
    } catch (...) {
      return false;
    }
  } else {
    const auto r = std::from_chars(text.data(), text.data() + text.size(), out);
    return r.ec == std::errc() && r.ptr == text.data() + text.size();
  }
}

using Setter = std::function<bool(Params&, const std::string&)>;

template <class Group, class T>
Setter field(Group Params::*group, T Group::*member) {
  return [group, member](Params& p, const std::string& v) {
    return parse_number(v, p.*group.*member);
  };
}

const std::map<std::string, Setter>& setters() {
  static const std::map<std::string, Setter> table = {
      {"keypoints.hessian_threshold",
       field(&Params::keypoints, &KeypointParams::hessian_threshold)},
      {"keypoints.hessian_octaves", field(&Params::keypoints, &KeypointParams::hessian_octaves)},
      {"keypoints.hessian_levels", field(&Params::keypoints, &KeypointParams::hessian_levels)},
      {"keypoints.model_scales", field(&Params::keypoints, &KeypointParams::model_scales)},
      {"keypoints.model_merge_distance",
       field(&Params::keypoints, &KeypointParams::model_merge_distance)},
      {"keypoints.max_model_keypoints",
       field(&Params::keypoints, &KeypointParams::max_model_keypoints)},
      {"keypoints.mser_delta", field(&Params::keypoints, &KeypointParams::mser_delta)},
      {"keypoints.mser_min_area", field(&Params::keypoints, &KeypointParams::mser_min_area)},
      {"keypoints.mser_max_area", field(&Params::keypoints, &KeypointParams::mser_max_area)},
      {"graph.min_distance", field(&Params::graph, &GraphParams::min_distance)},
      {"graph.max_distance", field(&Params::graph, &GraphParams::max_distance)},
      {"graph.scene_sample_distance", field(&Params::graph, &GraphParams::scene_sample_distance)},
      {"graph.max_anisotropy", field(&Params::graph, &GraphParams::max_anisotropy)},
      {"graph.scene_sampling",
       [](Params& p, const std::string& v) {
         if (v == "random")
           p.graph.scene_sampling = SceneSampling::kRandom;
         else if (v == "strongest")
           p.graph.scene_sampling = SceneSampling::kStrongest;
         else
           return false;
         return true;
       }},
      {"descriptor.blur_sigma", field(&Params::descriptor, &DescriptorParams::blur_sigma)},
      {"descriptor.profile_length", field(&Params::descriptor, &DescriptorParams::profile_length)},
      {"descriptor.coefficients", field(&Params::descriptor, &DescriptorParams::coefficients)},
      {"descriptor.parallel_offset",
       field(&Params::descriptor, &DescriptorParams::parallel_offset)},
      {"descriptor.similarity_threshold",
       field(&Params::descriptor, &DescriptorParams::similarity_threshold)},
      {"descriptor.vertex_descriptor",
       [](Params& p, const std::string& v) {
         if (v == "none")
           p.descriptor.vertex_descriptor = VertexDescriptor::kNone;
         else if (v == "sift")
           p.descriptor.vertex_descriptor = VertexDescriptor::kSift;
         else
           return false;
         return true;
       }},
      {"descriptor.encoding",
       [](Params& p, const std::string& v) {
         return parse_descriptor_encoding(v, p.descriptor.encoding);
       }},
      {"descriptor.vertex_threshold",
       field(&Params::descriptor, &DescriptorParams::vertex_threshold)},
      {"ransac.confidence", field(&Params::ransac, &RansacParams::confidence)},
      {"ransac.max_iterations", field(&Params::ransac, &RansacParams::max_iterations)},
      {"ransac.inlier_threshold", field(&Params::ransac, &RansacParams::inlier_threshold)},
      {"ransac.min_inliers", field(&Params::ransac, &RansacParams::min_inliers)},
      {"ransac.min_inlier_keygraphs", field(&Params::ransac, &RansacParams::min_inlier_keygraphs)},
      {"ransac.max_scale_change", field(&Params::ransac, &RansacParams::max_scale_change)},
      {"ransac.max_perspective", field(&Params::ransac, &RansacParams::max_perspective)},
      {"ransac.min_verification_z", field(&Params::ransac, &RansacParams::min_verification_z)},
      {"ransac.max_instances", field(&Params::ransac, &RansacParams::max_instances)},
      {"ransac.seed", field(&Params::ransac, &RansacParams::seed)},
  };
  return table;
}

}  // namespace

bool parse_descriptor_encoding(const std::string& text, DescriptorEncoding& out) {
  if (text == "float32") {
    out = DescriptorEncoding::kFloat32;
  } else if (text == "int16") {
    out = DescriptorEncoding::kInt16;
  } else if (text == "int8") {
    out = DescriptorEncoding::kInt8;
  } else {
    return false;
  }
  return true;
}

Status apply_param_override(const std::string& assignment, Params& params) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    return {StatusCode::kInvalidArgument, "--set takes NAME=VALUE, got '" + assignment + "'"};
  const std::string name = assignment.substr(0, eq), value = assignment.substr(eq + 1);
  const auto it = setters().find(name);
  if (it == setters().end())
    return {StatusCode::kInvalidArgument, "unknown parameter '" + name + "'"};
  if (!it->second(params, value))
    return {StatusCode::kInvalidArgument, "bad value '" + value + "' for " + name};
  return Status::ok();
}

std::vector<std::string> param_names() {
  std::vector<std::string> names;
  for (const auto& [name, setter] : setters()) names.push_back(name);
  return names;
}

}  // namespace kg
