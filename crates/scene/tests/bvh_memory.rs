//! Memory of the BVH per triangle (issue #11's scale item: a 10M-triangle scene under 100
//! bytes per triangle of peak memory), counted by a global allocator over a 200K-triangle
//! height field (the shape of `validation/loadtime/make_big_mesh.py`'s grid).
//!
//! - What an `Accel` keeps: the 8-wide triangle layout (36 bytes), the index map (4) and the
//!   BVH8 nodes; before the per-primitive copy of the vertices was dropped it kept 48 bytes
//!   more, and the conversion's reserve of one 80-byte node per primitive (about 170 in all).
//! - The peak of a build in eight parts, the path of scenes above 2M primitives: a single
//!   build peaks at about 230 bytes per triangle above the mesh (heaptrack), the parts at a
//!   fraction of it.

use glam::Vec3;
use radia_scene::{shape::Shape, Accel, Geometry, Mesh};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator, only counting.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let live = LIVE.fetch_add(layout.size(), Relaxed) + layout.size();
        PEAK.fetch_max(live, Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// An n × n vertex grid, two triangles per cell.
fn grid(n: u32) -> Mesh {
    let mut positions = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (x, z) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
            positions.push(Vec3::new(x, 0.05 * (6.0 * x).sin() * (5.0 * z).cos(), z));
        }
    }
    let mut indices = Vec::with_capacity(2 * ((n - 1) * (n - 1)) as usize);
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            indices.push([a, a + n, a + 1]);
            indices.push([a + 1, a + n, a + n + 1]);
        }
    }
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

/// (kept, peak above the start) bytes per triangle of `build` over the grid.
fn bytes_per_triangle(build: impl Fn(&[Shape]) -> Accel) -> (f64, f64) {
    let shapes = vec![Shape::new(Geometry::Mesh(grid(317)), 0, None)];
    let triangles = 2.0 * 316.0 * 316.0;
    let start = LIVE.load(Relaxed);
    PEAK.store(start, Relaxed);
    let accel = build(&shapes);
    let kept = LIVE.load(Relaxed) - start;
    let peak = PEAK.load(Relaxed) - start;
    assert_eq!(accel.len(), 199_712);
    (kept as f64 / triangles, peak as f64 / triangles)
}

/// One test, so that no other test's allocations run concurrently with the counts.
#[test]
fn bvh_bytes_per_triangle() {
    let (kept, _) = bytes_per_triangle(Accel::build);
    let (chunked_kept, chunked_peak) = bytes_per_triangle(|s| Accel::build_with_chunks(s, 0));
    eprintln!("kept {kept:.1} B/tri; chunked: kept {chunked_kept:.1}, peak {chunked_peak:.1}");
    assert!(kept < 60.0, "an Accel keeps {kept:.1} bytes per triangle");
    assert!(chunked_kept < 60.0, "{chunked_kept:.1} bytes per triangle");
    assert!(
        chunked_peak < 80.0,
        "a build in parts peaks at {chunked_peak:.1} bytes per triangle"
    );
}
