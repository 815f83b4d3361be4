//! Geometric trap shapes and their distance functions (pure maths).

/// A shape in the z-plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A single point.
    Point {
        /// Its position.
        at: [f64; 2],
    },
    /// An infinite line through `at` with unit direction `dir`.
    Line {
        /// A point on the line.
        at: [f64; 2],
        /// Unit direction.
        dir: [f64; 2],
    },
    /// Two perpendicular lines through `at`, the first along `dir`.
    Cross {
        /// The crossing point.
        at: [f64; 2],
        /// Unit direction of the first arm.
        dir: [f64; 2],
    },
    /// A circle.
    Circle {
        /// Its centre.
        at: [f64; 2],
        /// Its radius.
        radius: f64,
    },
}

impl Shape {
    /// Unit direction for an angle in degrees, measured from the real axis.
    pub fn direction(angle_degrees: f64) -> [f64; 2] {
        let a = angle_degrees.to_radians();
        [a.cos(), a.sin()]
    }

    /// Euclidean distance from `z` to the shape.
    #[inline]
    pub fn distance(&self, z: [f64; 2]) -> f64 {
        self.distance_from_metric(self.metric(z))
    }

    /// The quantity kernels keep a running minimum of: the distance itself, or for a point
    /// its square (sqrt is monotone and correctly rounded, so the root of the minimum equals
    /// the minimum of the roots bit for bit, at one root per orbit instead of one per step).
    /// The vectorised kernel repeats these exact operations lane by lane.
    #[inline]
    pub fn metric(&self, z: [f64; 2]) -> f64 {
        match *self {
            Shape::Point { at } => norm2(sub(z, at)),
            Shape::Line { at, dir } => cross(sub(z, at), dir).abs(),
            Shape::Cross { at, dir } => {
                let v = sub(z, at);
                cross(v, dir).abs().min(dot(v, dir).abs())
            }
            Shape::Circle { at, radius } => (norm2(sub(z, at)).sqrt() - radius).abs(),
        }
    }

    /// The distance a (minimum of) [`Shape::metric`] stands for.
    #[inline]
    pub fn distance_from_metric(&self, m: f64) -> f64 {
        if let Shape::Point { .. } = self { m.sqrt() } else { m }
    }
}

#[inline]
fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[inline]
fn norm2(a: [f64; 2]) -> f64 {
    a[0] * a[0] + a[1] * a[1]
}

#[inline]
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

#[inline]
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances() {
        let p = Shape::Point { at: [1.0, 1.0] };
        assert_eq!(p.distance([4.0, 5.0]), 5.0);
        let l = Shape::Line { at: [0.0, 1.0], dir: [1.0, 0.0] };
        assert_eq!(l.distance([7.0, -2.0]), 3.0);
        let c = Shape::Cross { at: [0.0, 0.0], dir: [1.0, 0.0] };
        assert_eq!(c.distance([3.0, 0.5]), 0.5);
        assert_eq!(c.distance([0.25, 3.0]), 0.25);
        let o = Shape::Circle { at: [0.0, 0.0], radius: 2.0 };
        assert_eq!(o.distance([0.0, 0.5]), 1.5);
        assert_eq!(o.distance([3.0, 4.0]), 3.0);
    }
}
