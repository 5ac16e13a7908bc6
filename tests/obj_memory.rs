//! The OBJ memory estimate is an upper bound: the allocator's peak while
//! loading a model and making its meshes stays below
//! `obj::memory_needed` on adversarial shapes (one huge fan, one face
//! repeated, short indices) and an ordinary model; endless inputs stop at
//! the budget.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use aerial::mesh::obj::{load_obj, memory_needed, model_meshes, ModelOptions};

/// Counts live bytes and their peak.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
/// One measurement at a time (tests run on several threads).
static SERIAL: Mutex<()> = Mutex::new(());

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc(layout);
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        System.dealloc(p, layout);
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Peak bytes allocated (above what was live before) by loading `text`
/// as a model and making its meshes, and the estimate.
fn measure(text: &str, triangles: u64) -> (u64, u64) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.obj");
    std::fs::write(&path, text).unwrap();
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let model = load_obj(&path).unwrap();
    let meshes = model_meshes(&model, &ModelOptions::default(), "m.obj").unwrap();
    let triangles_made: usize = meshes.iter().map(|(m, _)| m.triangle_count()).sum();
    drop((model, meshes));
    let peak = (PEAK.load(Ordering::Relaxed) - before) as u64;
    assert!(triangles_made as u64 <= triangles);
    (peak, memory_needed(text.len() as u64, triangles))
}

#[test]
fn obj_memory_estimate_bounds_the_measured_peak() {
    let n = 60_000u64;
    let mut shapes = Vec::new();
    // One face: a fan of n distinct vertices.
    let mut fan = String::new();
    for i in 0..n {
        let a = i as f64 / n as f64 * std::f64::consts::TAU;
        fan += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    fan += "f";
    for i in 1..=n {
        fan += &format!(" {i}");
    }
    fan += "\n";
    shapes.push(("one-face fan", fan, n - 2));
    // The shortest corners: a fan over three vertices, one digit each.
    let mut short = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nf");
    for i in 0..n {
        short += &format!(" {}", i % 3 + 1);
    }
    short += "\n";
    shapes.push(("fan of one-digit indices", short, n - 2));
    // One face repeated.
    let repeated = format!(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\n{}",
        "f 1 2 3\n".repeat(n as usize)
    );
    shapes.push(("repeated face", repeated, n));
    // An ordinary grid with UVs and normals.
    let side = 120usize;
    let mut grid = String::new();
    for j in 0..=side {
        for i in 0..=side {
            grid += &format!("v {i} {j} {}\nvt {} {}\nvn 0 0 1\n", (i * j) % 7, i, j);
        }
    }
    for j in 0..side {
        for i in 0..side {
            let k = j * (side + 1) + i + 1;
            let (a, b, c, d) = (k, k + 1, k + side + 2, k + side + 1);
            grid += &format!("f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c} {d}/{d}/{d}\n");
        }
    }
    shapes.push(("grid of quads", grid, 2 * (side * side) as u64));
    for (name, text, triangles) in shapes {
        let (peak, estimate) = measure(&text, triangles);
        println!(
            "{name}: {} bytes, {triangles} triangles: peak {peak} bytes, estimate {estimate} \
             ({:.2} of it)",
            text.len(),
            peak as f64 / estimate as f64
        );
        assert!(
            peak <= estimate,
            "{name}: peak {peak} > estimate {estimate}"
        );
    }
}
