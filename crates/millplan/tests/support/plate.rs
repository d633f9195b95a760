//! A test part: a 60 × 60 mm plate, top at z = 0, 5 mm thick, as an ASCII
//! STL (two triangles on top, two below).

use std::path::Path;

pub fn plate(path: &Path) {
    let tri = |n: [f64; 3], v: [[f64; 3]; 3]| {
        let mut s = format!("facet normal {} {} {}\nouter loop\n", n[0], n[1], n[2]);
        for p in v {
            s += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s + "endloop\nendfacet\n"
    };
    let (a, b, c, d) = ([0., 0., 0.], [60., 0., 0.], [60., 60., 0.], [0., 60., 0.]);
    let (e, f, g, h) = (
        [0., 0., -5.],
        [60., 0., -5.],
        [60., 60., -5.],
        [0., 60., -5.],
    );
    let mut s = String::from("solid plate\n");
    s += &tri([0., 0., 1.], [a, b, c]);
    s += &tri([0., 0., 1.], [a, c, d]);
    s += &tri([0., 0., -1.], [e, g, f]);
    s += &tri([0., 0., -1.], [e, h, g]);
    s += "endsolid plate\n";
    std::fs::write(path, s).expect("write");
}
