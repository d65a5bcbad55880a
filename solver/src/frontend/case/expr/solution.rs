//! The solution `u` in expressions: coefficients of a nonlinear problem
//! are evaluated at a value of u, and differentiated with respect to it.

use super::{ExprError, Expression, Scope, Slot};
use exmex::prelude::*;

impl Expression {
    /// The value at `point`, time `t` and solution value `u`.
    ///
    /// ```
    /// use hasse_solver::frontend::case::expr::Scope;
    /// let k = Scope::new().with_solution().parse("1 + x * u^2").unwrap();
    /// assert!(k.uses_solution() && !k.is_constant());
    /// assert_eq!(k.eval_with(&[2.0], 0.0, 3.0), 19.0);
    /// // ∂k/∂u = 2 x u, by exmex's symbolic differentiation.
    /// let dk = k.derivative_u().unwrap();
    /// assert_eq!(dk.eval_with(&[2.0], 0.0, 3.0), 12.0);
    /// // Without `u`, the derivative is 0.
    /// assert_eq!(Scope::new().parse("x").unwrap().derivative_u().unwrap().eval_with(&[2.0], 0.0, 3.0), 0.0);
    /// ```
    pub fn eval_with(&self, point: &[f64], t: f64, u: f64) -> f64 {
        self.evaluate(point, t, u)
    }

    /// ∂/∂u of the expression, symbolically (exmex's partial derivative);
    /// an error for operators exmex cannot differentiate (comparisons,
    /// `if`, `&&`, `||`, rounding).
    pub fn derivative_u(&self) -> Result<Expression, ExprError> {
        let index = self
            .slots
            .iter()
            .position(|slot| matches!(slot, Slot::Solution));
        let Some(index) = index else {
            return Scope::new().parse("0");
        };
        let not_differentiable = |reason: String| ExprError::NotDifferentiable {
            text: self.text.clone(),
            reason,
        };
        if self.regions.is_some() {
            return Err(not_differentiable("it is given per region".into()));
        }
        let flat = (*self.flat)
            .clone()
            .partial(index)
            .map_err(|e| not_differentiable(e.msg().to_string()))?;
        Ok(Expression {
            text: format!("∂({})/∂u", self.text),
            flat: Box::new(flat),
            slots: self.slots.clone(),
            constant: false,
            uses_time: self.uses_time,
            uses_solution: true,
            regions: None,
        })
    }
}
