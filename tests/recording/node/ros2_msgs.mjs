// ROS 2 message definitions (.msg texts, fields as in ROS 2 common_interfaces / rcl_interfaces),
// written here independently of flowsteer's C++ so that rewrite_for_replay.mjs is an independent
// writer. Comments are left out; field names, types, array bounds and defaults are ROS 2's.
//
// fullDefinition("nav_msgs/msg/Odometry") returns rosbag2's "ros2msg" complete definition: the
// type's text, then for each dependency (depth-first, each once) a line of 80 '=', a line
// "MSG: pkg/Type" (see fullDefinition) and that type's text.

export const MSG_TEXTS = {
  "builtin_interfaces/msg/Time": `int32 sec
uint32 nanosec
`,
  "std_msgs/msg/Header": `builtin_interfaces/Time stamp
string frame_id
`,
  "geometry_msgs/msg/Vector3": `float64 x
float64 y
float64 z
`,
  "geometry_msgs/msg/Point": `float64 x
float64 y
float64 z
`,
  "geometry_msgs/msg/Quaternion": `float64 x 0
float64 y 0
float64 z 0
float64 w 1
`,
  "geometry_msgs/msg/Pose": `Point position
Quaternion orientation
`,
  "geometry_msgs/msg/PoseWithCovariance": `Pose pose
float64[36] covariance
`,
  "geometry_msgs/msg/Twist": `Vector3  linear
Vector3  angular
`,
  "geometry_msgs/msg/TwistWithCovariance": `Twist twist
float64[36] covariance
`,
  "geometry_msgs/msg/Transform": `Vector3 translation
Quaternion rotation
`,
  "geometry_msgs/msg/TransformStamped": `std_msgs/Header header
string child_frame_id
Transform transform
`,
  "nav_msgs/msg/Odometry": `std_msgs/Header header
string child_frame_id
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
`,
  "tf2_msgs/msg/TFMessage": `geometry_msgs/TransformStamped[] transforms
`,
  "sensor_msgs/msg/CompressedImage": `std_msgs/Header header
string format
uint8[] data
`,
  "sensor_msgs/msg/RegionOfInterest": `uint32 x_offset
uint32 y_offset
uint32 height
uint32 width
bool do_rectify
`,
  "sensor_msgs/msg/CameraInfo": `std_msgs/Header header
uint32 height
uint32 width
string distortion_model
float64[] d
float64[9]  k
float64[9]  r
float64[12] p
uint32 binning_x
uint32 binning_y
RegionOfInterest roi
`,
};

const PRIMITIVES = new Set([
  "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
  "int32", "uint32", "int64", "uint64", "string", "wstring",
]);

// Complex field types of a .msg text, as fully qualified "pkg/msg/Type" names.
function dependencies(fullName) {
  const pkg = fullName.split("/")[0];
  const deps = [];
  for (const raw of MSG_TEXTS[fullName].split("\n")) {
    const line = raw.replace(/#.*/, "").trim();
    if (!line) continue;
    const type = line.split(/\s+/)[0].replace(/\[.*\]$/, "").replace(/<=\d+$/, "");
    if (PRIMITIVES.has(type) || /^w?string<=/.test(type)) continue;
    if (/^\S+\s+\w+\s*=/.test(line)) continue; // constant
    const parts = type.split("/");
    const qualified = parts.length === 1 ? `${pkg}/msg/${parts[0]}`
      : parts.length === 2 ? `${parts[0]}/msg/${parts[1]}` : type;
    if (!(qualified in MSG_TEXTS)) throw new Error(`ros2_msgs: no definition for ${qualified} (in ${fullName})`);
    deps.push(qualified);
  }
  return deps;
}

export const SEPARATOR = "=".repeat(80);

export function fullDefinition(fullName) {
  if (!(fullName in MSG_TEXTS)) throw new Error(`ros2_msgs: unknown type ${fullName}`);
  const order = [];
  const seen = new Set([fullName]);
  const visit = (name) => {
    for (const dep of dependencies(name)) {
      if (seen.has(dep)) continue;
      seen.add(dep);
      order.push(dep);
      visit(dep);
    }
  };
  visit(fullName);
  let text = MSG_TEXTS[fullName];
  // "MSG: pkg/Type" (no "/msg/"): @foxglove/rosmsg resolves "std_msgs/Header" fields only against
  // a section named exactly "std_msgs/Header".
  for (const dep of order) text += `${SEPARATOR}\nMSG: ${dep.replace("/msg/", "/")}\n${MSG_TEXTS[dep]}`;
  return text;
}
