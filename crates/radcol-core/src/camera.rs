//! A pinhole camera: where a rendered image looks from and to.

use glam::DVec3;

/// A pinhole camera with a vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// A point the camera looks at (the image centre).
    pub target: DVec3,
    /// The up direction (need not be orthogonal to the view direction).
    pub up: DVec3,
    /// Vertical field of view, degrees, in (0, 180).
    pub fov_y_deg: f64,
}

impl Camera {
    /// Parses `eye,target,up,fov` as ten comma-separated numbers
    /// (`ex,ey,ez,tx,ty,tz,ux,uy,uz,fov`), rejecting degenerate cameras.
    pub fn parse(text: &str) -> Result<Self, String> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        if parts.len() != 10 {
            return Err(format!(
                "camera '{text}': expected 10 numbers ex,ey,ez,tx,ty,tz,ux,uy,uz,fov_degrees, got {}",
                parts.len()
            ));
        }
        let mut v = [0.0; 10];
        for (o, p) in v.iter_mut().zip(&parts) {
            *o = p
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("camera '{text}': '{p}' is not a finite number"))?;
        }
        let cam = Camera {
            eye: DVec3::new(v[0], v[1], v[2]),
            target: DVec3::new(v[3], v[4], v[5]),
            up: DVec3::new(v[6], v[7], v[8]),
            fov_y_deg: v[9],
        };
        cam.validate()?;
        Ok(cam)
    }

    /// Checks that eye ≠ target, up is not parallel to the view direction and
    /// the field of view lies in (0, 180) degrees.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [("eye", self.eye), ("target", self.target), ("up", self.up)] {
            if !v.is_finite() {
                return Err(format!("camera: {name} {v} is not finite"));
            }
        }
        let fwd = self.target - self.eye;
        // Differences and lengths of coordinates near f64's limits overflow.
        if !fwd.is_finite() || !fwd.length().is_finite() || !self.up.length().is_finite() {
            let e = |v: DVec3| format!("({:e}, {:e}, {:e})", v.x, v.y, v.z);
            return Err(format!(
                "camera: eye {} and target {} are too far apart for double precision (their distance overflows)",
                e(self.eye),
                e(self.target)
            ));
        }
        if fwd.length() <= 0.0 {
            return Err("camera: eye and target coincide".into());
        }
        let sine = fwd.normalize().cross(self.up).length();
        if sine.is_nan() || sine <= 1e-9 * self.up.length() {
            return Err("camera: up is zero or parallel to the view direction".into());
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(format!(
                "camera: field of view {} must lie strictly between 0 and 180 degrees",
                self.fov_y_deg
            ));
        }
        Ok(())
    }

    /// Orthonormal (right, up, forward) of the view.
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let fwd = (self.target - self.eye).normalize();
        let right = fwd.cross(self.up).normalize();
        let up = right.cross(fwd);
        (right, up, fwd)
    }

    /// The unit direction of the ray through image point (x, y) in pixels of a
    /// `width` × `height` image (x right, y down, pixel centres at +0.5).
    pub fn ray_direction(&self, x: f64, y: f64, width: u32, height: u32) -> DVec3 {
        let (right, up, fwd) = self.basis();
        let tan = (self.fov_y_deg.to_radians() * 0.5).tan();
        let aspect = width as f64 / height as f64;
        let u = (2.0 * x / width as f64 - 1.0) * tan * aspect;
        let v = (1.0 - 2.0 * y / height as f64) * tan;
        (fwd + right * u + up * v).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_rejects() {
        let c = Camera::parse("0,0,-5, 0,0,0, 0,1,0, 40").unwrap();
        assert_eq!(c.eye, DVec3::new(0.0, 0.0, -5.0));
        // The centre ray looks at the target.
        let d = c.ray_direction(50.0, 50.0, 100, 100);
        assert!((d - DVec3::Z).length() < 1e-15);
        assert!(Camera::parse("0,0,0,0,0,0,0,1,0,40")
            .unwrap_err()
            .contains("coincide"));
        assert!(Camera::parse("0,0,-5,0,0,0,0,0,1,40")
            .unwrap_err()
            .contains("parallel"));
        assert!(Camera::parse("0,0,-5,0,0,0,0,1,0,180")
            .unwrap_err()
            .contains("between"));
        assert!(Camera::parse("1,2,3").unwrap_err().contains("10 numbers"));
        assert!(Camera::parse("0,0,-5,0,0,0,0,1,0,x")
            .unwrap_err()
            .contains("'x'"));
    }

    /// Image x grows to the right of the view: with the eye on -z looking at +z
    /// and up +y, right is -x.
    #[test]
    fn right_handed_view() {
        let c = Camera::parse("0,0,-5,0,0,0,0,1,0,60").unwrap();
        assert!(c.ray_direction(99.0, 50.0, 100, 100).x < 0.0);
        assert!(c.ray_direction(50.0, 1.0, 100, 100).y > 0.0);
    }
}
