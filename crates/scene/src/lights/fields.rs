//! A light's fields as the scene file gives them, read by its kind ([`super::LightKind::load`]).

use std::collections::BTreeMap;

use glam::Vec3;
use ron::Value;

use crate::error::{ErrorKind, SceneError};

/// The fields of one light in a scene file, by name (`name` excluded), as RON values: its
/// kind reads them with the checks each needs, and an error names the field.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Fields(pub BTreeMap<String, Value>);

/// A [`ErrorKind::BadValue`] about `field`.
pub(crate) fn bad(field: &'static str, message: impl Into<String>) -> SceneError {
    SceneError::new(ErrorKind::BadValue {
        field,
        message: message.into(),
    })
}

fn number(field: &'static str, v: &Value) -> Result<f32, SceneError> {
    match v {
        Value::Number(n) => Ok(n.into_f64() as f32),
        Value::Option(Some(v)) => number(field, v),
        _ => Err(bad(field, "must be a number")),
    }
}

impl Fields {
    /// The fields given as (name, value) pairs.
    pub fn of<'a>(pairs: impl IntoIterator<Item = (&'a str, Value)>) -> Self {
        Self(pairs.into_iter().map(|(k, v)| (k.to_owned(), v)).collect())
    }

    fn get(&self, field: &'static str) -> Option<&Value> {
        self.0
            .get(field)
            .filter(|v| !matches!(v, Value::Option(None)))
    }

    /// An optional number.
    ///
    /// # Errors
    /// When it is not a finite number.
    pub fn opt_f32(&self, field: &'static str) -> Result<Option<f32>, SceneError> {
        let Some(v) = self.get(field) else {
            return Ok(None);
        };
        let x = number(field, v)?;
        if x.is_finite() {
            Ok(Some(x))
        } else {
            Err(bad(field, format!("{x} is not finite")))
        }
    }

    /// A number, `default` when it is not given.
    ///
    /// # Errors
    /// When it is not a finite number.
    pub fn f32_or(&self, field: &'static str, default: f32) -> Result<f32, SceneError> {
        Ok(self.opt_f32(field)?.unwrap_or(default))
    }

    /// An optional triple of finite numbers.
    ///
    /// # Errors
    /// When it is not three finite numbers.
    pub fn opt_v3(&self, field: &'static str) -> Result<Option<Vec3>, SceneError> {
        let v = match self.get(field) {
            None => return Ok(None),
            Some(Value::Option(Some(v))) => v.as_ref(),
            Some(v) => v,
        };
        let Value::Seq(items) = v else {
            return Err(bad(field, "must be three numbers, (x, y, z)"));
        };
        if items.len() != 3 {
            return Err(bad(field, "must be three numbers, (x, y, z)"));
        }
        let mut out = [0.0; 3];
        for (o, item) in out.iter_mut().zip(items) {
            *o = number(field, item)?;
        }
        let v = Vec3::from(out);
        if v.is_finite() {
            Ok(Some(v))
        } else {
            Err(bad(field, format!("{v} is not finite")))
        }
    }

    /// A triple of finite numbers that must be given.
    ///
    /// # Errors
    /// When it is missing or not three finite numbers.
    pub fn v3(&self, field: &'static str) -> Result<Vec3, SceneError> {
        self.opt_v3(field)?.ok_or_else(|| bad(field, "is missing"))
    }

    /// A colour or power: three finite numbers ≥ 0 that must be given.
    ///
    /// # Errors
    /// When it is missing, not finite, or has a negative component.
    pub fn non_negative3(&self, field: &'static str) -> Result<Vec3, SceneError> {
        let v = self.v3(field)?;
        if v.min_element() >= 0.0 {
            Ok(v)
        } else {
            Err(bad(field, format!("{v} has a negative component")))
        }
    }

    /// A unit direction from a non-zero vector that must be given.
    ///
    /// # Errors
    /// When it is missing, not finite or zero.
    pub fn direction(&self, field: &'static str) -> Result<Vec3, SceneError> {
        let v = self.v3(field)?;
        if v.length_squared() == 0.0 {
            return Err(bad(field, "the direction must not be zero"));
        }
        Ok(v.normalize())
    }

    /// An angle in degrees, in [0, `max`], as radians; `default` when it is not given.
    ///
    /// # Errors
    /// When it is out of range.
    pub fn angle_or(&self, field: &'static str, default: f32, max: f32) -> Result<f32, SceneError> {
        let degrees = self.f32_or(field, default)?;
        if (0.0..=max).contains(&degrees) {
            Ok(degrees.to_radians())
        } else {
            Err(bad(
                field,
                format!("{degrees} must be in [0, {max}] degrees"),
            ))
        }
    }

    /// The unit axis from `position` towards the point `target` names (which must be given).
    ///
    /// # Errors
    /// When the target is missing, not finite, or is the position.
    pub fn towards(&self, position: Vec3, target: &'static str) -> Result<Vec3, SceneError> {
        let axis = self.v3(target)? - position;
        if axis.length_squared() == 0.0 {
            return Err(bad(target, "the target must differ from the position"));
        }
        Ok(axis.normalize())
    }
}
