//! Which pedestal parameters a fit estimates, and how the equations of eq. 4
//! are combined (the paper's Table 2 variants).

use plinth_shared::regression::{EquationMode, Parameter, PARAMETERS};

/// The set of pedestal parameters estimated by a fit; the others are fixed at
/// zero. Always kept in θ order (k_y, k_z, m, c_y, c_z).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Model {
    included: [bool; PARAMETERS],
}

/// Why a `--model` list could not be parsed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ModelError {
    /// A name that is not one of k_y, k_z, m, c_y, c_z.
    #[error("unknown pedestal parameter `{0}` (expected k_y, k_z, m, c_y, c_z)")]
    Unknown(String),
    /// A name listed twice.
    #[error("pedestal parameter `{0}` listed twice")]
    Repeated(String),
    /// No parameter at all.
    #[error("the model needs at least one pedestal parameter")]
    Empty,
}

impl Model {
    /// All five parameters: k_y, k_z, m, c_y, c_z (the paper's damped model).
    pub const FULL: Model = Model {
        included: [true; PARAMETERS],
    };

    /// k_y, k_z, m with c_y = c_z = 0 (the paper's undamped model).
    pub const UNDAMPED: Model = Model {
        included: [true, true, true, false, false],
    };

    /// The default model of an equation mode: all five for R&I; k_y, k_z, m
    /// for R, I and R+I, which the paper used on undamped pedestals only.
    pub fn default_for(mode: EquationMode) -> Model {
        match mode {
            EquationMode::RealAndImag => Model::FULL,
            _ => Model::UNDAMPED,
        }
    }

    /// A model from the parameters it estimates (any order, no repeats).
    pub fn from_parameters(parameters: &[Parameter]) -> Result<Model, ModelError> {
        let mut included = [false; PARAMETERS];
        for &p in parameters {
            if included[p as usize] {
                return Err(ModelError::Repeated(p.name().to_string()));
            }
            included[p as usize] = true;
        }
        if !included.contains(&true) {
            return Err(ModelError::Empty);
        }
        Ok(Model { included })
    }

    /// Parses a comma-separated list such as `k_y,k_z,m`.
    pub fn parse(text: &str) -> Result<Model, ModelError> {
        let mut parameters = Vec::new();
        for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            parameters
                .push(Parameter::from_name(name).ok_or_else(|| ModelError::Unknown(name.into()))?);
        }
        Model::from_parameters(&parameters)
    }

    /// True when the model estimates `p`.
    pub fn includes(&self, p: Parameter) -> bool {
        self.included[p as usize]
    }

    /// The estimated parameters in θ order.
    pub fn parameters(&self) -> Vec<Parameter> {
        Parameter::ALL
            .into_iter()
            .filter(|&p| self.includes(p))
            .collect()
    }

    /// The parameters fixed at zero, in θ order.
    pub fn fixed(&self) -> Vec<Parameter> {
        Parameter::ALL
            .into_iter()
            .filter(|&p| !self.includes(p))
            .collect()
    }

    /// Names of the estimated parameters (formats.md `"model"`).
    pub fn names(&self) -> Vec<String> {
        self.parameters()
            .iter()
            .map(|p| p.name().to_string())
            .collect()
    }

    /// Number of estimated parameters.
    pub fn len(&self) -> usize {
        self.included.iter().filter(|&&b| b).count()
    }

    /// Always false: a model estimates at least one parameter.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.names().join(","))
    }
}

impl std::str::FromStr for Model {
    type Err = ModelError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Model::parse(s)
    }
}

/// The command-line and JSON name of an equation mode:
/// `r-and-i`, `r-plus-i`, `real`, `imag`.
pub fn mode_name(mode: EquationMode) -> &'static str {
    match mode {
        EquationMode::RealAndImag => "r-and-i",
        EquationMode::RealPlusImag => "r-plus-i",
        EquationMode::Real => "real",
        EquationMode::Imag => "imag",
    }
}

/// The paper's label of an equation mode (Table 2): R&I, R+I, R, I.
pub fn mode_label(mode: EquationMode) -> &'static str {
    match mode {
        EquationMode::RealAndImag => "R&I",
        EquationMode::RealPlusImag => "R+I",
        EquationMode::Real => "R",
        EquationMode::Imag => "I",
    }
}

/// Parses [`mode_name`]'s names back.
pub fn parse_mode(name: &str) -> Option<EquationMode> {
    [
        EquationMode::RealAndImag,
        EquationMode::RealPlusImag,
        EquationMode::Real,
        EquationMode::Imag,
    ]
    .into_iter()
    .find(|&m| mode_name(m) == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_prints_models() {
        assert_eq!(Model::parse("k_y,k_z,m").unwrap(), Model::UNDAMPED);
        assert_eq!(Model::parse(" m, k_z ,k_y,c_z,c_y").unwrap(), Model::FULL);
        assert_eq!(Model::FULL.to_string(), "k_y,k_z,m,c_y,c_z");
        assert_eq!(
            Model::parse("k_y,kz"),
            Err(ModelError::Unknown("kz".into()))
        );
        assert_eq!(Model::parse("m,m"), Err(ModelError::Repeated("m".into())));
        assert_eq!(Model::parse(""), Err(ModelError::Empty));
        assert_eq!(Model::UNDAMPED.fixed(), vec![Parameter::Cy, Parameter::Cz]);
    }

    #[test]
    fn mode_names_round_trip() {
        for m in [
            EquationMode::RealAndImag,
            EquationMode::RealPlusImag,
            EquationMode::Real,
            EquationMode::Imag,
        ] {
            assert_eq!(parse_mode(mode_name(m)), Some(m));
        }
    }
}
