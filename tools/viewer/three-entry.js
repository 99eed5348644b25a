// The parts of three.js the cgamesh viewer uses, bundled by build.mjs into one minified script
// that defines the global THREE (with OrbitControls from three's examples).
export {
  AmbientLight, Box3, BufferAttribute, BufferGeometry, CanvasTexture, Color, DirectionalLight, DoubleSide,
  FrontSide, Group, HemisphereLight, LineBasicMaterial, LineSegments, Mesh, MeshStandardMaterial,
  NearestFilter, PerspectiveCamera, RepeatWrapping, SRGBColorSpace, Scene, Sphere, Vector3, WebGLRenderer,
} from "three";
export { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
