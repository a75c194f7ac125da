//! Plots people read (issue 18, finding 6): the reflective surface drawn
//! over the panes' outlines, the legend beside the data, the top view a
//! height slice above the floor, and the trajectory plot. Checked on what
//! the drawing reports and on the decoded PNG.

use std::path::Path;
use std::sync::Arc;

use nalgebra::{Point3, Vector3};
use specular::classify::Class;
use specular::geometry::Plane;
use specular::io::map_ply::class_colour;
use specular::io::MapPoint;
use specular::reflect::BoundedPlane;
use specular::viz::legend::PixelRect;
use specular::viz::plots::{trajectory_png, TrajectorySeries};
use specular::viz::topdown::{
    corner_layers, topdown_layers, topdown_png, HeightSlice, Layer, TopdownDrawn,
};

/// The cyan of the panes' outlines.
const PANE: [u8; 3] = [0, 190, 210];

fn point(x: f64, y: f64, z: f64, class: Class) -> MapPoint {
    MapPoint {
        xyz: [x as f32, y as f32, z as f32],
        class,
        mirrored: false,
        confidence: 1.0,
    }
}

/// A 6 x 4 m room (floor z = 0, ceiling z = 3, walls) with a window pane on
/// y = 4 (x 1..5, z 0.5..2.5) whose glass points lie on it, reflections
/// beyond it, and the sensor path at 1.2 m.
fn room() -> (Vec<MapPoint>, Vec<BoundedPlane>, Vec<[f64; 3]>) {
    let mut pts = Vec::new();
    for i in 0..=60 {
        for j in 0..=40 {
            let (x, y) = (0.1 * i as f64, 0.1 * j as f64);
            pts.push(point(x, y, 0.0, Class::Normal));
            pts.push(point(x, y, 3.0, Class::Normal));
        }
    }
    for k in 0..=60 {
        for h in 0..=30 {
            let (t, z) = (0.1 * k as f64, 0.1 * h as f64);
            pts.push(point(t, 0.0, z, Class::Normal));
            if t < 4.0 {
                pts.push(point(0.0, t, z, Class::Normal));
                pts.push(point(6.0, t, z, Class::Normal));
            }
            if !(1.0..=5.0).contains(&t) || !(0.5..=2.5).contains(&z) {
                pts.push(point(t, 4.0, z, Class::Normal));
            } else {
                pts.push(point(t, 4.0, z, Class::Glass));
                pts.push(point(t, 6.0, z, Class::Reflection));
            }
        }
    }
    let plane = Plane::new(Vector3::new(0.0, -1.0, 0.0), 4.0).unwrap();
    let mut window = BoundedPlane::from_points(
        plane,
        [(1.0, 0.5), (5.0, 0.5), (5.0, 2.5), (1.0, 2.5)]
            .iter()
            .map(|&(x, z)| Point3::new(x, 4.0, z)),
    );
    window.panes = Some(Arc::new(vec![window.boundary.clone()]));
    let path = (0..=40).map(|k| [1.0 + 0.1 * k as f64, 2.0, 1.2]).collect();
    (pts, vec![window], path)
}

/// The decoded RGB image of a PNG file.
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Whether a pixel of colour `c` lies within `r` pixels of `(x, y)`.
fn colour_near(img: &(u32, u32, Vec<u8>), (x, y): (i32, i32), r: i32, c: [u8; 3]) -> bool {
    let (w, h, buf) = img;
    (-r..=r).any(|dy| {
        (-r..=r).any(|dx| {
            let (px, py) = (x + dx, y + dy);
            if px < 0 || py < 0 || px >= *w as i32 || py >= *h as i32 {
                return false;
            }
            let k = 3 * (py as usize * *w as usize + px as usize);
            buf[k..k + 3] == c
        })
    })
}

fn draw(slice: HeightSlice) -> (TopdownDrawn, (u32, u32, Vec<u8>), tempfile::TempDir) {
    let (pts, planes, path) = room();
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("topdown.png");
    let drawn = topdown_png(&png, &pts, &planes, &path, slice).unwrap();
    let img = decode(&png);
    (drawn, img, dir)
}

#[test]
fn the_reflective_surface_is_drawn_over_the_outlines() {
    for layers in [topdown_layers(), corner_layers()] {
        let at = |l: Layer| layers.iter().position(|&m| m == l).unwrap();
        let glass = at(Layer::Points {
            class: Class::Glass,
            mirrored: false,
        });
        assert!(glass > at(Layer::Panes), "{layers:?}");
        assert!(glass > at(Layer::Hulls), "{layers:?}");
    }
    // Drawn in that order, and the pane was drawn.
    let (drawn, img, _dir) = draw(HeightSlice { min: 0.3, max: 2.0 });
    let order: Vec<Layer> = drawn.panel.layers.iter().map(|(l, _)| *l).collect();
    assert_eq!(order, topdown_layers());
    assert_eq!(drawn.panel.count(Layer::Panes), 1);
    assert_eq!(drawn.panel.count(Layer::Hulls), 0, "a plane with panes");
    // In the image, the glass points show where the pane's outline passes,
    // and the pane's band shows beside them.
    let glass = class_colour(Class::Glass, false);
    let along: Vec<(i32, i32)> = (0..=30)
        .map(|k| drawn.panel.pixel(1.5 + 0.1 * k as f64, 4.0))
        .collect();
    let green = along
        .iter()
        .filter(|&&p| colour_near(&img, p, 1, glass))
        .count();
    let cyan = along
        .iter()
        .filter(|&&p| colour_near(&img, p, 5, PANE))
        .count();
    assert_eq!(green, along.len(), "glass pixels on the pane line");
    assert!(cyan * 10 >= along.len() * 9, "{cyan} of {}", along.len());
}

#[test]
fn the_legend_is_outside_the_data_area() {
    let (drawn, img, _dir) = draw(HeightSlice { min: 0.3, max: 2.0 });
    let legend = drawn.legend;
    assert!(!legend.intersects(&drawn.panel.data_area));
    assert!(legend.x1 - legend.x0 > 50 && legend.y1 - legend.y0 > 50);
    let image = PixelRect {
        x0: 0,
        y0: 0,
        x1: img.0 as i32,
        y1: img.1 as i32,
    };
    for (x, y) in [(legend.x0, legend.y0), (legend.x1 - 1, legend.y1 - 1)] {
        assert!(image.contains(x, y));
    }
    // The legend names what was drawn, e.g. the reflective surface's dot
    // is in it.
    let glass = class_colour(Class::Glass, false);
    let (w, _, buf) = &img;
    let in_legend = (legend.y0..legend.y1).any(|y| {
        (legend.x0..legend.x1).any(|x| {
            let k = 3 * (y as usize * *w as usize + x as usize);
            buf[k..k + 3] == glass
        })
    });
    assert!(in_legend);
}

#[test]
fn the_top_view_is_a_slice_above_the_floor() {
    let (pts, _, _) = room();
    let inside = |p: &MapPoint| (0.3..=2.0).contains(&(p.xyz[2] as f64));
    let (drawn, _img, _dir) = draw(HeightSlice { min: 0.3, max: 2.0 });
    let floor = drawn.floor.expect("a floor");
    assert!(floor.normal.z > 0.999 && floor.d.abs() < 0.01, "{floor:?}");
    assert_eq!(
        drawn.outside_slice,
        pts.iter().filter(|p| !inside(p)).count()
    );
    for class in [Class::Normal, Class::Glass, Class::Reflection] {
        let layer = Layer::Points {
            class,
            mirrored: false,
        };
        let want = pts.iter().filter(|p| p.class == class && inside(p)).count();
        assert_eq!(drawn.panel.count(layer), want, "{class:?}");
    }
    // Without a slice every point is drawn.
    let (all, _, _dir) = draw(HeightSlice::ALL);
    assert_eq!(all.floor, None);
    assert_eq!(all.outside_slice, 0);
    let normal = Layer::Points {
        class: Class::Normal,
        mirrored: false,
    };
    let want = pts.iter().filter(|p| p.class == Class::Normal).count();
    assert_eq!(all.panel.count(normal), want);
}

#[test]
fn the_trajectory_plot_overlays_its_series_with_the_legend_beside() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("trajectory.png");
    let truth: Vec<[f64; 2]> = (0..50).map(|k| [0.1 * k as f64, 0.0]).collect();
    let estimate: Vec<[f64; 2]> = truth.iter().map(|p| [p[0], 0.05 * p[0]]).collect();
    let series = [
        TrajectorySeries {
            name: "ground truth".into(),
            colour: [170, 170, 170],
            width: 7,
            points: truth,
        },
        TrajectorySeries {
            name: "estimated".into(),
            colour: [220, 30, 30],
            width: 2,
            points: estimate,
        },
    ];
    let drawn = trajectory_png(&png, "test", &series).unwrap();
    assert!(!drawn.legend.intersects(&drawn.data_area));
    let img = decode(&png);
    let (w, h, buf) = &img;
    let count = |c: [u8; 3]| {
        (0..(*w * *h) as usize)
            .filter(|k| buf[3 * k..3 * k + 3] == c)
            .count()
    };
    assert!(count([170, 170, 170]) > 500);
    assert!(count([220, 30, 30]) > 200);
}
