//! Moving objects: a deterministic animation of some of a scene's objects,
//! so culling is measured on scenes that change (paper 001 §4: bunnies
//! moving freely through the power plant). A mover drives round a closed
//! route at a steady speed; its pose is a function of the frame number
//! alone, so every mode and the reference see each object in the same place.

use glam::{DAffine3, DQuat, DVec3};

/// A closed polyline driven at constant speed, first point after the last.
#[derive(Clone, Debug, PartialEq)]
pub struct Route {
    points: Vec<DVec3>,
    /// Distance along the loop at which each point is reached.
    starts: Vec<f64>,
    length: f64,
}

impl Route {
    /// A loop through `points`; `None` unless it has some length.
    pub fn closed(points: Vec<DVec3>) -> Option<Route> {
        let mut starts = Vec::with_capacity(points.len());
        let mut length = 0.0;
        for (i, p) in points.iter().enumerate() {
            starts.push(length);
            length += p.distance(points[(i + 1) % points.len()]);
        }
        (length > 0.0 && length.is_finite()).then_some(Route { points, starts, length })
    }

    pub fn length(&self) -> f64 {
        self.length
    }

    /// Where a model facing +X stands at `distance` along the loop: turned
    /// about +Y to face the direction of travel and set on the route.
    pub fn placement(&self, distance: f64) -> DAffine3 {
        let (position, heading) = self.at(distance);
        let yaw = (-heading.z).atan2(heading.x);
        DAffine3::from_rotation_translation(DQuat::from_rotation_y(yaw), position)
    }

    /// The point at `distance` along the loop (wrapping), and the unit
    /// direction of travel there.
    pub fn at(&self, distance: f64) -> (DVec3, DVec3) {
        let d = distance.rem_euclid(self.length);
        // The last leg whose start is not beyond `d`; zero-length legs are
        // skipped because the next leg starts at the same distance.
        let leg = self.starts.partition_point(|&s| s <= d) - 1;
        let (a, b) = (self.points[leg], self.points[(leg + 1) % self.points.len()]);
        let along = b - a;
        let t = (d - self.starts[leg]) / along.length();
        (a + along * t, along.normalize())
    }
}

/// One object driving round a route.
#[derive(Clone, Debug, PartialEq)]
pub struct Mover {
    pub object: u32,
    route: Route,
    /// Scene units per frame.
    speed: f64,
    /// Distance along the route at frame 0.
    start: f64,
    /// The object's place in its model (a cluster's origin), applied before
    /// the model is put on the route.
    local: DAffine3,
}

impl Mover {
    pub fn new(object: u32, route: Route, speed: f64, start: f64, local: DAffine3) -> Mover {
        Mover {
            object,
            route,
            speed,
            start,
            local,
        }
    }

    /// The object's transform at `frame`.
    pub fn transform(&self, frame: u32) -> DAffine3 {
        self.route.placement(self.start + self.speed * f64::from(frame)) * self.local
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Route {
        Route::closed(vec![
            DVec3::ZERO,
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 10.0),
            DVec3::new(0.0, 0.0, 10.0),
        ])
        .unwrap()
    }

    #[test]
    fn a_route_is_driven_at_constant_speed_and_wraps() {
        let r = square();
        assert_eq!(r.length(), 40.0);
        assert_eq!(r.at(5.0), (DVec3::new(5.0, 0.0, 0.0), DVec3::X));
        assert_eq!(r.at(15.0), (DVec3::new(10.0, 0.0, 5.0), DVec3::Z));
        assert_eq!(r.at(35.0), (DVec3::new(0.0, 0.0, 5.0), DVec3::NEG_Z));
        assert_eq!(r.at(45.0), r.at(5.0));
        assert_eq!(r.at(-5.0), r.at(35.0));
        assert!(Route::closed(vec![DVec3::ONE, DVec3::ONE]).is_none());
    }

    #[test]
    fn a_mover_faces_where_it_drives() {
        let m = Mover::new(0, square(), 2.5, 0.0, DAffine3::IDENTITY);
        // Frame 6: 15 units along, on the leg towards +Z.
        let t = m.transform(6);
        assert!(t.translation.distance(DVec3::new(10.0, 0.0, 5.0)) < 1e-12);
        let nose = t.transform_vector3(DVec3::X);
        assert!(
            nose.distance(DVec3::Z) < 1e-12,
            "the model's +X points along +Z, got {nose}"
        );
        assert_eq!(m.transform(16), m.transform(0), "one lap is 16 frames");
    }
}
