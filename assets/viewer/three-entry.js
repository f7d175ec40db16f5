// The parts of three.js the crest viewer uses, bundled into one minified IIFE (global THREE).
export {
  AmbientLight, BufferAttribute, BufferGeometry, Color, DirectionalLight, DoubleSide,
  Float32BufferAttribute, Line, LineBasicMaterial, Mesh, MeshLambertMaterial, PerspectiveCamera,
  Points, PointsMaterial, Raycaster, Scene, Sphere, Spherical, Vector2, Vector3, WebGLRenderer,
  SphereGeometry, MeshBasicMaterial, Box3, LineSegments, EdgesGeometry, BoxGeometry, SRGBColorSpace,
} from 'three';
