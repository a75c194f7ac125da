//! What stands in a drawn scene besides its structure: furniture, people
//! and plants on a floor, and the street outside a facade (ground, trees,
//! cars, facing buildings). Everything is placed through
//! [`Draft::solid`], so nothing overlaps and the path stays clear.

use glam::{DVec2, DVec3};

use super::draft::Draft;

impl Draft {
    /// Furniture, people and plants scattered over the floor rectangle
    /// `min`-`max` at floor height `z`: about `count` items, each placed
    /// where it overlaps nothing and keeps clear of the path.
    pub fn clutter(&mut self, min: DVec2, max: DVec2, z: f64, count: usize) {
        let wood = self.diffuse("furniture", 0.15, 0.7);
        let cloth = self.diffuse("person", 0.1, 0.5);
        let leaves = self.diffuse("plant", 0.3, 0.5);
        let mut placed = 0;
        for _ in 0..count * 4 {
            if placed == count {
                break;
            }
            let (size, material) = match self.int(0, 5) {
                // Desk, table.
                0 | 1 => (
                    DVec3::new(
                        self.uniform(1.0, 1.8),
                        self.uniform(0.6, 0.9),
                        self.uniform(0.7, 0.78),
                    ),
                    wood.clone(),
                ),
                // Cabinet, shelf.
                2 => (
                    DVec3::new(
                        self.uniform(0.4, 1.2),
                        self.uniform(0.35, 0.6),
                        self.uniform(0.8, 2.0),
                    ),
                    wood.clone(),
                ),
                // Chair, box.
                3 => (
                    DVec3::new(
                        self.uniform(0.4, 0.6),
                        self.uniform(0.4, 0.6),
                        self.uniform(0.45, 1.0),
                    ),
                    wood.clone(),
                ),
                // A person standing.
                4 => (
                    DVec3::new(
                        self.uniform(0.35, 0.5),
                        self.uniform(0.25, 0.35),
                        self.uniform(1.55, 1.9),
                    ),
                    cloth.clone(),
                ),
                // A plant.
                _ => (
                    DVec3::new(
                        self.uniform(0.4, 0.8),
                        self.uniform(0.4, 0.8),
                        self.uniform(0.6, 1.8),
                    ),
                    leaves.clone(),
                ),
            };
            let size = if self.chance(0.5) {
                DVec3::new(size.y, size.x, size.z)
            } else {
                size
            };
            let room = max - min - size.truncate();
            if room.x <= 0.05 || room.y <= 0.05 {
                continue;
            }
            let at = min + DVec2::new(self.uniform(0.0, room.x), self.uniform(0.0, room.y));
            let lo = at.extend(z);
            if self.solid(lo, lo + size, &material) {
                placed += 1;
                if placed == count {
                    break;
                }
            }
        }
    }

    /// The world outside a facade: ground at height `ground` over the
    /// rectangle `min`-`max`, with trees, cars and facing buildings
    /// scattered over it (keeping `keep_out` free: the building).
    pub fn street(&mut self, min: DVec2, max: DVec2, ground: f64, keep_out: (DVec2, DVec2)) {
        let pavement = self.diffuse("pavement", 0.12, 0.35);
        self.floor_rect(min, max, ground, &pavement);
        let tree = self.diffuse("tree", 0.3, 0.5);
        let car = self.diffuse("car", 0.1, 0.5);
        let building = self.diffuse("building", 0.2, 0.6);
        let n = self.int(3, 9);
        for _ in 0..n * 3 {
            let (size, m) = match self.int(0, 2) {
                0 => {
                    let w = self.uniform(0.6, 1.5);
                    (DVec3::new(w, w, self.uniform(3.0, 8.0)), tree.clone())
                }
                1 => (
                    DVec3::new(
                        self.uniform(3.8, 4.8),
                        self.uniform(1.7, 1.9),
                        self.uniform(1.4, 1.8),
                    ),
                    car.clone(),
                ),
                _ => (
                    DVec3::new(
                        self.uniform(6.0, 20.0),
                        self.uniform(6.0, 15.0),
                        self.uniform(6.0, 20.0),
                    ),
                    building.clone(),
                ),
            };
            let room = max - min - size.truncate();
            if room.x <= 0.0 || room.y <= 0.0 {
                continue;
            }
            let at = min + DVec2::new(self.uniform(0.0, room.x), self.uniform(0.0, room.y));
            let (klo, khi) = keep_out;
            let hi = at + size.truncate();
            let inside_keep = at.x < khi.x + 1.0
                && klo.x - 1.0 < hi.x
                && at.y < khi.y + 1.0
                && klo.y - 1.0 < hi.y;
            if !inside_keep {
                self.solid(
                    at.extend(ground),
                    (at + size.truncate()).extend(ground + size.z),
                    &m,
                );
            }
        }
    }
}
