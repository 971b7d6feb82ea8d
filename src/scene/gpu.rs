//! GpuScene: a Scene on the GPU (triangles in BVH order, BVH nodes, materials, lights and
//! their sampling tables).
