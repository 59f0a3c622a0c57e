"""Parse AgentSpeak text into a ``Program`` (grammar in ``agentspeak.lark``; this module only transforms).

Errors are ``AslSyntaxError`` naming ``file:line:col``, quoting the line with a caret under the
column, and saying what was expected. ``parse_program_all_errors`` keeps going after an error
(re-synchronising at the next clause) so ``faultmas asl check`` can report every error at once.
"""
from __future__ import annotations

import os
import re
import threading
from pathlib import Path

from agentspeak.lark_loader import lalr_parser  # first: it refuses lark-parser 0.12 with the fix
from lark import Lark, Token, Transformer
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from agentspeak.errors import AslSyntaxError
from agentspeak.namespaces import NsError, NsScope, needs_scope, unique_ns_id
from agentspeak.ground_terms import read_ground_term
from agentspeak.source_text import read_source
from agentspeak.nesting import MAX_NESTING, first_too_deep_bracket, nesting_depth, too_deep_message
from agentspeak.program import (
    ACHIEVE, ADD, BEL, DEL, META, TEST, Achieve, AchieveNew, Action, AddBel, AddBelEnd, AddBelNew,
    AddPlan, Constraint, DelBel, DelBelNew, ExecVar, Fork, If, InternalAction, Plan, PlanTerm,
    Instr, Program, RemovePlan, Rule, Test, Trigger, TriggerInstr, UpdBel, While, For, copy_program,
    with_sub_plans,
)
from agentspeak.patterns import PATTERNS, PatternError, apply_pattern
from agentspeak.stdlib.functions import FUNCTIONS, check_function_name, rule_function
from agentspeak.stdlib.registry import set_program_reader
from agentspeak.terms import (
    DEFAULT_NS_NAME, And, AnnotatedVar, Arith, ArithmeticError_, Func, Literal, Not, NsTerm, Or, Rel, Term, Var,
    is_ground, make_list, resolve,
)

_GRAMMAR = Path(__file__).with_name("agentspeak.lark")

# human names for the grammar's terminals, used in "expected ..." messages
TOKEN_LABELS = {
    "DOT": "'.'", "COMMA": "','", "SEMICOLON": "';'", "COLON": "':'", "ARROW": "'<-'", "LPAR": "'('",
    "RPAR": "')'", "LSQB": "'['", "RSQB": "']'", "LBRACE": "'{'", "RBRACE": "'}'", "ATOM": "an atom",
    "VAR": "a variable", "UNNAMED_VAR": "a variable", "NUMBER": "a number", "STRING": "a string",
    "IA_NAME": "an internal action", "QATOM": "a quoted atom", "BANG": "'!'", "QMARK": "'?'",
    "PLUS": "'+'", "MINUS": "'-'", "NEG": "'-'", "TILDE": "'~'", "AT": "'@'", "BAR": "'|'", "AND": "'&'",
    "REL": "a relational operator", "ADD": "'+' or '-'", "MUL": "'*', '/', 'div' or 'mod'", "POW": "'**'",
    "NOT": "'not'", "IF": "'if'", "ELSE": "'else'", "ELIF": "'elif'", "WHILE": "'while'", "FOR": "'for'",
    "__ANON_0": "':-'", "$END": "end of file", "CIRCUMFLEX": "'^'",
}

_INFIX = {  # operator -> (precedence, right-assoc)
    "|": (1, False), "&": (2, False),
    "<": (4, False), "<=": (4, False), ">": (4, False), ">=": (4, False), "==": (4, False),
    "\\==": (4, False), "=": (4, False), "=..": (4, False),
    "+": (5, False), "-": (5, False), "*": (6, False), "/": (6, False), "div": (6, False),
    "mod": (6, False), "**": (7, True),
}
_PREFIX_NOT_PREC = 3      # `not` binds looser than relational operators (Jason's log_expr_factor)
_INFIX_TYPES = {"BAR", "AND", "REL", "ADD", "MUL", "POW"}
_PREFIX_TYPES = {"NOT", "NEG", "PLUS"}


def _is_ia_name(name: str) -> bool:
    return "." in name and name[0] != "'"


class _ParenBody(tuple):
    """The formulas of a body written in parentheses (``(!a ||| !b)``) where a formula stands."""


def _bodies_only_as_formulas(*names: str):
    """Wrap the named transformer methods so that a body in parentheses among their parts (a term, a
    context, a condition) is a syntax error, as in Jason, instead of a value nobody can use."""
    def decorate(cls):
        for name in names:
            def checked(self, c, _f=getattr(cls, name)):
                for x in c:
                    if type(x) is _ParenBody:
                        raise _BadInput("a body in parentheses (formulas joined by ';', '|&|' or '|||') "
                                        "stands only where a body formula does, not as a term or condition")
                return _f(self, c)
            setattr(cls, name, checked)
        return cls
    return decorate


@_bodies_only_as_formulas("belief", "rule", "plan", "if_stmt", "elif_part", "while_stmt", "for_stmt",
                          "plan_term_full", "plan_term_ctx", "prefixed", "expr", "atomic_formula",
                          "annotations", "list")
class _ToProgram(Transformer):
    """One method per grammar rule; builds runtime objects directly (no parse tree kept)."""

    def __init__(self, source_file: str) -> None:
        super().__init__(visit_tokens=False)
        self.source_file = source_file
        self.vars: dict[str, Var] = {}
        self.line = 0
        self.warnings: list[str] = []
        self.prefix_nots: set[int] = set()
        self.op_depth: dict[int, int] = {}   # id of an operator node -> how many operators deep (``_op``)
        self.user_functions: dict = {}   # name -> FunctionSpec, from register_function directives

    # -- helpers -----------------------------------------------------------------------------
    def _var(self, name: str) -> Var:
        if name == "_":
            return Var("_")
        v = self.vars.get(name)
        if v is None:
            v = self.vars[name] = Var(name)
        return v

    def _end_clause(self) -> None:
        self.vars = {}

    # -- top level -----------------------------------------------------------------------------
    def start(self, items):
        return items

    def belief(self, c):
        lit = c[0]
        self._end_clause()
        return ("belief", lit, self.line)

    def rule(self, c):
        head, body = c
        self._end_clause()
        return ("rule", Rule(head, body, self.source_file, self.line), self.line)

    def initial_goal(self, c):
        self._end_clause()
        return ("goal", c[0], self.line)

    def directive(self, c):
        self._end_clause()
        lit = c[0]
        if type(lit) is Literal and lit.functor == "register_function":
            # registered now: the clauses after it are parsed with the function known (as in Jason)
            return ("register_function", self._register_function(lit), self.line)
        return ("directive", lit, self.line)

    def _register_function(self, lit: Literal) -> str | None:
        """``{ register_function("ns.f", Arity, "rule") }``; returns a warning, or None."""
        args = lit.args
        if len(args) == 1:
            return (f"register_function({args[0]}) names a Java class; write the function in "
                    f"Python with @arith_function instead (ignored)")
        if (len(args) != 3 or type(args[0]) is not str or type(args[1]) is not int
                or type(args[2]) is not str):
            return f"expected register_function(\"ns.name\", Arity, \"rule\"), got {lit} (ignored)"
        name, arity, predicate = args
        problem = check_function_name(name) if name not in self.user_functions else None
        if problem is not None:
            return problem
        self.user_functions[name] = rule_function(name, arity, predicate)
        return None

    def directive_begin(self, c):
        self._end_clause()
        return ("begin", c[1], getattr(c[0], "line", self.line))

    def directive_end(self, c):
        return ("end", None, getattr(c[0], "line", self.line))

    def plan(self, c):
        label, trigger, context, _gc, goal_condition, _arrow, body = c
        context = _no_true(context)
        plan = Plan(trigger, context, body or (), label, self.source_file, trigger_line(trigger, self))
        plan.goal_condition = goal_condition
        self._end_clause()
        return ("plan", plan, plan.line)

    def sub_plans(self, c):
        """``{ plans }`` after a plan: the plans (each with its own block attached)."""
        plans: list = []
        for kind, value, line in c:
            if kind == "plan":
                plans.append(value)
            elif not plans:
                raise _BadInput("a block of sub-plans must follow a plan")
            else:
                plans[-1] = with_sub_plans(plans[-1], value)
        return ("sub_plans", plans, c[0][2] if c else self.line)

    def label_named(self, c):
        return _not_function(c[0])

    def label_var(self, c):
        """``@L`` in a plan term (``{@L +!g <- b}``): unifies with a plan's label."""
        return self.var_literal(c)

    def label_anon(self, c):
        annots = c[0]
        return Literal("", (), annots[0] or None, False, annots[1])

    # triggers
    def _trig(op, kind):  # noqa: N805 - a factory used in the class body
        def build(self, c):
            self.trigger_line = self.line
            return Trigger(op, kind, _not_function(c[0]))
        return build

    trig_add_bel = _trig(ADD, BEL)
    trig_del_bel = _trig(DEL, BEL)
    trig_add_achieve = _trig(ADD, ACHIEVE)
    trig_del_achieve = _trig(DEL, ACHIEVE)
    trig_add_test = _trig(ADD, TEST)
    trig_del_test = _trig(DEL, TEST)
    trig_meta_achieve = _trig(META, ACHIEVE)
    trig_meta_test = _trig(META, TEST)

    # -- bodies ---------------------------------------------------------------------------------
    def body(self, c):
        out = []
        for instr in c:
            if instr is None:
                continue
            if type(instr) is tuple:  # a body in parentheses: its formulas in place
                out.extend(instr)
                continue
            if isinstance(instr, Trigger):
                instr = TriggerInstr(instr, self.line)
            out.append(instr)
        return tuple(out)

    def _branch(self, x):
        if isinstance(x, Trigger):
            x = TriggerInstr(x, self.line)
        if isinstance(x, tuple):  # a body in parentheses
            return x
        return (x,) if x is not None else ()

    def op_and(self, c):
        return "|&|"

    def op_or(self, c):
        return "|||"

    def op_seq(self, c):
        return ";"

    def paren_body(self, c):
        """``( F1 op F2 op ... )`` with op ``;`` < ``|||`` < ``|&|`` (Jason's precedence): a body."""
        units = [u if isinstance(u, Instr) else self.formula([u]) for u in c[0::2]]
        ops = c[1::2]

        def split(lo: int, hi: int, op: str) -> list:
            cut = [i for i in range(lo, hi - 1) if ops[i] == op]
            bounds = [lo] + [i + 1 for i in cut] + [hi]
            return [(bounds[k], bounds[k + 1]) for k in range(len(bounds) - 1)]

        def build(lo: int, hi: int, level: int) -> tuple:
            if hi - lo == 1:
                return self._branch(units[lo])
            op = (";", "|||", "|&|")[level]
            parts = split(lo, hi, op)
            if len(parts) == 1:
                return build(lo, hi, level + 1)
            bodies = tuple(build(a, b, level + 1) for a, b in parts)
            if op == ";":
                return tuple(instr for body in bodies for instr in body)
            return (Fork("or" if op == "|||" else "and", bodies, self.line),)
        return _ParenBody(build(0, len(units), 0))

    def fork_or(self, c):
        return Fork("or", tuple(self._as_body(x) for x in c), self.line)

    def fork_and(self, c):
        return Fork("and", tuple(self._as_body(x) for x in c), self.line)

    def _as_body(self, x):
        if isinstance(x, Fork) and x.kind == "and":
            return (x,)
        return self._branch(x)

    def _one(cls):  # noqa: N805
        def build(self, c):
            return cls(c[0], self.line)
        return build

    achieve = _one(Achieve)
    achieve_new = _one(AchieveNew)
    test = _one(Test)
    add_bel = _one(AddBel)
    add_bel_end = _one(AddBelEnd)
    add_bel_new = _one(AddBelNew)
    del_bel = _one(DelBel)
    del_bel_new = _one(DelBelNew)
    upd_bel = _one(UpdBel)
    remove_plan = _one(RemovePlan)

    def add_plan(self, c):
        return AddPlan(c[0], False, self.line)

    def add_plan_end(self, c):
        return AddPlan(c[0], True, self.line)

    def formula(self, c):
        t = c[0]
        if type(t) is _ParenBody:
            return tuple(t)
        if type(t) is Func:  # `math.max(1,2)` alone is not a formula: an internal action (that fails)
            t = _not_function(t)
        if isinstance(t, Literal):
            if t.functor == "true" and not t.args and not t.neg:
                return None
            if _is_ia_name(t.functor):
                return InternalAction(t, self.line)
            return Action(t, self.line)
        if isinstance(t, Var):
            return ExecVar(t, self.line)
        if isinstance(t, PlanTerm) and t.body is not None:
            return ExecVar(t, self.line)
        if isinstance(t, (Rel, And, Or, Not)):
            return Constraint(t, self.line)
        raise _BadInput(f"'{_shown(t)}' is not a body formula (expected an action, a goal, a belief update or a test)")

    def if_stmt(self, c):
        cond, block = c[0], c[1]
        branches = [(cond, block)]
        else_body = None
        for part in c[2:]:
            if part is None:
                continue
            if part[0] == "elif":
                branches.append((part[1], part[2]))
            else:
                else_body = part[1]
        return If(tuple(branches), else_body, self.line)

    def elif_part(self, c):
        return ("elif", c[0], c[1])

    def else_part(self, c):
        return ("else", c[0])

    def while_stmt(self, c):
        return While(c[0], c[1], self.line)

    def for_stmt(self, c):
        return For(c[0], c[1], self.line)

    def block(self, c):
        return c[0] or ()

    # -- plan terms -------------------------------------------------------------------------------
    def plan_term_full(self, c):
        label, trigger, context, _gc, goal_condition, _arrow, body = c
        context = _no_true(context)
        plan = Plan(trigger, context, body or (), label, self.source_file, self.line)
        plan.goal_condition = goal_condition
        return PlanTerm(plan=plan)

    def plan_term_ctx(self, c):
        label, trigger, context = c
        context = _no_true(context)
        return PlanTerm(plan=Plan(trigger, context, (), label, self.source_file, self.line))

    def plan_term_body(self, c):
        body = c[0]
        if len(body) == 1 and isinstance(body[0], TriggerInstr):
            return PlanTerm(plan=Plan(body[0].trigger, None, (), None, self.source_file, self.line))
        return PlanTerm(body=body)

    def plan_term_empty(self, c):
        """``{}``: the empty plan body (Jason's meta-programming demos end a recursion on it)."""
        return PlanTerm(body=())

    def plan_term_rule(self, c):
        return PlanTerm(rule=Rule(c[0], c[1], self.source_file, self.line))

    # -- expressions -------------------------------------------------------------------------------
    def _op(self, node: Term, *operands: Term) -> Term:
        """``node``, an operator applied to ``operands``, refused past ``MAX_NESTING`` operators deep. An
        operator chain (``- - - … 1``, ``a - 1 - 1 …``, ``not not … a``) nests without brackets, so the bracket
        scan before parsing lets it through, and the callbacks here see it before the depth walk after
        parsing: a Literal made with such an annotation (it sorts its annotations: a recursive comparison)
        or an error message that printed one overflowed the C stack of the compiled build (SIGSEGV, found
        by the fuzz campaign). Counted as the chain is built (bracketed operands count as one level: the
        bracket scan bounds them), so the refusal costs a dictionary look-up per operator."""
        depth = self.op_depth
        level = 1 + max([depth.get(id(x), 0) for x in operands])
        if level > MAX_NESTING:
            raise _BadInput(too_deep_message())
        depth[id(node)] = level
        return node

    def prefixed(self, c):
        tok, inner = c
        kind = tok.type
        if kind == "NOT":
            node = self._op(Not(inner), inner)
            self.prefix_nots.add(id(node))
            return node
        if kind == "PLUS":
            return inner
        if type(inner) in (int, float):
            return -inner
        return self._op(Arith("-", inner), inner)

    def expr(self, c):
        """Precedence climbing over ``operand (operator operand)*``."""
        pos = [0]
        prefix_nots = self.prefix_nots

        def climb(min_prec, left=None):
            if left is None:
                left = c[pos[0]]
                pos[0] += 1
                if type(left) is Not and id(left) in prefix_nots and min_prec <= _PREFIX_NOT_PREC:
                    # `not X > 3` is `not (X > 3)`: `not` binds looser than relational operators
                    prefix_nots.discard(id(left))
                    arg = climb(_PREFIX_NOT_PREC + 1, left.arg)
                    left = self._op(Not(arg), arg)
            while pos[0] < len(c):
                op = c[pos[0]].value
                prec, right_assoc = _INFIX[op]
                if prec < min_prec:
                    break
                pos[0] += 1
                right = climb(prec if right_assoc else prec + 1)
                left = self._op(_binary(op, left, right), left, right)
            return left

        return climb(0)

    log_expr = expr
    list_elem = expr
    log_expr_nm = expr

    def paren(self, c):
        return c[0]

    def number(self, c):
        text = c[0].value
        if "." in text or "e" in text or "E" in text:
            value = float(text)
            return int(value) if value.is_integer() and abs(value) < 2 ** 53 else value
        if len(text) > _MAX_INT_DIGITS:  # Python refuses to convert longer ones (a ValueError)
            raise _BadInput(f"integer literal of {len(text)} digits is too long (at most {_MAX_INT_DIGITS})")
        return int(text)

    def string(self, c):
        # Jason's lexer unescapes only \n and \" (other escapes stay as written)
        return c[0].value[1:-1].replace("\\n", "\n").replace('\\"', '"')

    # -- literals and terms ---------------------------------------------------------------------
    def literal(self, c):
        return c[0]

    def neg_literal(self, c):
        lit = _not_function(c[0])
        return Literal(lit.functor, lit.args, lit.annots, True, lit.annot_tail)

    def var_literal(self, c):
        tok, annots = c
        v = self._var(tok.value)
        if annots is not None and (annots[0] or annots[1] is not None):
            return AnnotatedVar(v, annots[0], annots[1])
        return v

    def atomic_formula(self, c):
        functor = c[0]
        annots = c[-1]
        args = tuple(a for a in c[1:-1] if a is not None) if len(c) > 2 else ()
        if annots is not None:
            return Literal(functor, args, annots[0] or None, False, annots[1])
        if "." in functor:  # a registered function with this arity is a function call (Jason's parser)
            spec = self.user_functions.get(functor)
            if spec is None or not spec.accepts(len(args)):
                spec = FUNCTIONS.get(functor, len(args))
            if spec is not None:
                return Func(functor, args, spec)
        return Literal(functor, args)

    def functor(self, c):
        tok = c[0]
        self.line = tok.line
        text = tok.value
        # a quoted atom keeps its quotes, as in Jason: 'a b' prints quoted and 'abc' is not abc
        return text

    # name spaces: the functor keeps the name space as written (``tv::cfp``, ``::cfp``, ``default::cfp``) and a
    # variable name space is an NsTerm; agentspeak.namespaces resolves both once the clause is complete
    def ns_prefix(self, c):
        tok = c[0]
        self.line = tok.line
        if tok.type == "NS_SEP":
            return ""
        if tok.type == "ATOM" or tok.type == "LOCAL_NS":
            return tok.value
        return self._var(tok.value)

    def ns_literal(self, c, neg: bool = False):
        ns, lit = c[0], _not_function(c[-1])
        if type(ns) is str:
            return Literal(f"{ns}::{lit.functor}", lit.args, lit.annots, neg or lit.neg, lit.annot_tail)
        return NsTerm(ns, Literal(lit.functor, lit.args, lit.annots, neg, lit.annot_tail) if neg else lit)

    def ns_neg_literal(self, c):
        return self.ns_literal(c, True)

    def ns_var_literal(self, c):
        ns, body = c[0], self.var_literal(c[1:])
        return NsTerm(Literal(ns) if type(ns) is str else ns, body)

    def annotations(self, c):
        items, tail = self._items(c)
        return (tuple(items), tail)

    def list(self, c):
        items, tail = self._items(c)
        return make_list(items, tail)

    def _items(self, c):
        items = []
        tail = None
        it = iter(c)
        for x in it:
            if _is_token(x) and x.type == "BAR":
                t = next(it)
                if _is_token(t):
                    tail = self._var(t.value)
                else:
                    tail = t
                break
            if x is not None:
                items.append(x)
        return items, tail


def _no_true(context: Term) -> Term:
    """A context that is just ``true`` is no context (Jason prints ``+!g : true <- b`` as ``+!g <- b``)."""
    if type(context) is Literal and context.functor == "true" and not context.args and not context.neg \
            and context.annots is None:
        return None
    return context


def _not_function(t: Term) -> Term:
    """A function call where a literal is needed (a trigger, a label, a formula) is that literal."""
    return Literal(t.name, t.args) if type(t) is Func else t


def _is_token(x) -> bool:
    """A lexer token (Lark's, or lark_cython's, which is not a ``lark.Token``)."""
    return type(x) is Token or (hasattr(x, "type") and hasattr(x, "value") and not isinstance(x, (Literal, Var)))


def trigger_line(trigger: Trigger, t: _ToProgram) -> int:
    return getattr(t, "trigger_line", t.line)


def _binary(op: str, left: Term, right: Term) -> Term:
    if op == "|":
        return Or(left, right)
    if op == "&":
        return And(left, right)
    if op in ("+", "-", "*", "/", "div", "mod", "**"):
        return Arith(op, left, right)
    return Rel(op, left, right)


_MAX_INT_DIGITS = 4300  # CPython's limit on int(str) (sys.get_int_max_str_digits)


class _BadInput(Exception):
    """A clause that parses but is not valid AgentSpeak (raised inside the transformer)."""


_SHOWN_CHARS = 80   # of a term quoted in an error message


def _shown(t: Term) -> str:
    """``t`` as an error message quotes it: at most ``_SHOWN_CHARS`` characters. An operator chain nests without
    brackets (``.print - - - … t(1)``, ``a - 1 - 1 …``), so the bracket scan before parsing lets it through,
    and the transformer sees it before the depth check after parsing: printed whole, 20,000 levels deep, it
    overflowed the C stack of the compiled build (found by the fuzz campaign); it is the depth error now."""
    if nesting_depth(t) > MAX_NESTING:
        raise _BadInput(too_deep_message())
    text = str(t)
    return text if len(text) <= _SHOWN_CHARS else text[:_SHOWN_CHARS - 3] + "..."


def parse_program(text: str, source_file: str = "<string>", base_dir: str | None = None,
                  _seen: set | None = None, source_path: tuple = (), namespace: str = DEFAULT_NS_NAME) -> Program:
    """Parse a whole agent program; raise ``AslSyntaxError`` at the first error.

    A file without includes is parsed once per process: later calls with the same text get a copy
    whose plans and rules are their own objects (labels, flags) but share the immutable terms, so
    100 agents of one source share one set of compiled contexts (and stay in the CPU's caches)."""
    # the functions known decide whether `ns.f(...)` is a call: a function registered later must not
    # meet a parse made before it
    key = (text, source_file, len(FUNCTIONS.functions), namespace)
    # an expanded program is kept only for a file parsed on its own (``_seen`` None): inside another file's
    # includes it lacks what that file included before it (helper.asl, included after faulty.asl, skips
    # geometry.asl), and kept so, an agent of helper.asl alone later in the process ran without geometry.asl
    cached = _PARSED.get(key) or (_PARSED.get(key + (tuple(source_path),)) if _seen is None else None)
    if cached is not None:
        return copy_program(cached)
    program, errors = _parse(text, source_file, stop_at_first=True, namespace=namespace)
    if errors:
        raise errors[0]
    if program.__dict__.pop("local_namespaces", False):
        # its local name spaces (#<n>ns) are new at each parse: each inclusion has private ones (not cached)
        if program.__dict__.get("includes"):
            program = _expand_includes(program, source_file, base_dir, _seen, source_path)
        return program
    if program.__dict__.get("includes"):
        # the included files are read now; the expanded program is kept like any other (100 agents that
        # include the same library parse it once)
        program = _expand_includes(program, source_file, base_dir, _seen, source_path)
        if _seen is not None:
            return program  # depends on what the including file included before: not kept (see above)
        key = key + (tuple(source_path),)
    if len(_PARSED) >= _PARSED_MAX:
        try:
            del _PARSED[next(iter(_PARSED))]  # the oldest
        except (KeyError, RuntimeError, StopIteration):  # another thread got there first
            pass
    _PARSED[key] = program
    return copy_program(program)


_PARSED: dict[tuple, Program] = {}
"""(text, file) -> the program as parsed (never handed out: callers get copies)."""
_PARSED_MAX = 32


def parse_program_all_errors(text: str, source_file: str = "<string>") -> tuple[Program, list[AslSyntaxError]]:
    """Parse, collecting every syntax error (for ``faultmas asl check``)."""
    program, errors = _parse(text, source_file, stop_at_first=False)
    if not errors:
        try:
            program = _expand_includes(program, source_file, None, None)
        except AslSyntaxError as exc:
            errors.append(exc)
    return program, errors


_CLAUSE_START = re.compile(r"^(?=[+\-@!^a-z~{])", re.M)

#: ``faultmas asl check`` reports at most this many syntax errors of one file, then says it stopped.
MAX_ERRORS = 100


def _parse(text: str, source_file: str, stop_at_first: bool, namespace: str = DEFAULT_NS_NAME) -> tuple[Program, list]:
    program = Program(source_file=source_file)
    scope = NsScope(namespace) if needs_scope(text, namespace) else None
    errors: list[AslSyntaxError] = []
    too_deep = first_too_deep_bracket(text)
    if too_deep is not None:  # refused before the parser spends seconds on it (agentspeak/nesting.py)
        line = text.count("\n", 0, too_deep) + 1
        column = too_deep - (text.rfind("\n", 0, too_deep) + 1) + 1
        source_line = text.split("\n")[line - 1]
        errors.append(AslSyntaxError(too_deep_message(), source_file, line, column,
                                     None if len(source_line) > 200 else source_line))  # no caret far off
        return program, errors
    offset_line = 0
    remaining = text
    while True:
        try:
            items = _parse_items(remaining, source_file)
            scope = _collect(items, program, offset_line, scope)
            break
        except (UnexpectedInput, _BadInputAt) as exc:
            err = _to_syntax_error(exc, text, remaining, source_file, offset_line)
            errors.append(err)
            if stop_at_first:
                break
            if len(errors) >= MAX_ERRORS:  # each one re-parses the rest: 30,000 errors took minutes (issue 22)
                errors.append(AslSyntaxError(f"too many errors ({MAX_ERRORS}); the rest of the file is not checked",
                                             source_file, err.line, None, None))
                break
            # re-synchronise: go on at the next line, after the error, that can start a clause
            lines = remaining.split("\n")
            next_start = None
            for i in range(max((err.line or 1) - offset_line, 1), len(lines)):
                if _CLAUSE_START.match(lines[i]):
                    next_start = i
                    break
            if next_start is None:
                break
            offset_line += next_start
            remaining = "\n".join(lines[next_start:])
    return program, errors


class _BadInputAt(Exception):
    def __init__(self, message: str, line: int) -> None:
        super().__init__(message)
        self.message, self.line = message, line


_PARSE_LOCK = threading.Lock()
_TRANSFORMER = _ToProgram("<none>")
_INLINE_PARSER: Lark | None = None


def _speedups() -> dict:
    """lark_cython (Lark's LALR parser and lexer compiled with Cython) when installed: ~1.5x faster.

    Same grammar, same tokens (plus ``.value``/``.type``/``.line`` as Lark's); pure Lark otherwise.
    """
    try:
        import lark_cython
    except ImportError:
        return {}
    return {"_plugins": lark_cython.plugins}


def _parse_items(text: str, source_file: str) -> list:
    """Parse with the transformer called during parsing (LALR: no tree is built, which is faster).

    One parser and one transformer per process, reset before each parse (a lock keeps threads apart).
    """
    global _INLINE_PARSER
    with _PARSE_LOCK:
        if _INLINE_PARSER is None:
            _INLINE_PARSER = lalr_parser(_GRAMMAR, lexer="contextual",
                                  maybe_placeholders=True, transformer=_TRANSFORMER, **_speedups())
        t = _TRANSFORMER
        t.source_file, t.vars, t.line, t.trigger_line = source_file, {}, 0, 0
        t.prefix_nots = set()
        t.op_depth = {}
        t.user_functions = {}
        try:
            return _INLINE_PARSER.parse(text)
        except _BadInput as exc:
            raise _BadInputAt(str(exc), t.line) from exc
        except RecursionError:  # an expression nested so deeply that the parser's own recursion gave up
            raise _BadInputAt(too_deep_message(), t.line) from None


def _collect(items, program: Program, offset_line: int, scope: NsScope | None = None) -> NsScope | None:
    """Put the parsed clauses into ``program`` (resolving name spaces with ``scope``, made at the first
    namespace directive if the text needed none before); returns the scope."""
    previous = None
    target = program  # inside `{ begin pattern(...) } ... { end }`: the block's own program
    blocks: list = []  # (directive, line, the program around the block); directive None: a name-space block
    for kind, value, line in items:
        if scope is not None:
            value = scope.clause(kind, value)
        if kind in ("directive", "begin") and _is_namespace_directive(value):
            if scope is None:
                scope = NsScope()
            try:
                if kind == "begin":
                    scope.begin(value)
                    blocks.append((None, line, target))
                else:
                    scope.declare(value)
            except NsError as exc:
                raise _BadInputAt(str(exc), line) from None
            program.__dict__["local_namespaces"] = program.__dict__.get("local_namespaces") or scope.declared_local
            continue
        if kind == "end" and blocks and blocks[-1][0] is None:
            blocks.pop()
            scope.end()
            continue
        if kind == "directive" and isinstance(value, Literal) and value.functor == "include":
            value = _include_ns(value, scope)
        if kind == "sub_plans":  # Jason(ER): the block belongs to the plan just before it
            if previous != "plan":
                raise _BadInputAt("a block of sub-plans '{ +!g <- ... }' must follow a plan", line)
            for sp in value:
                _shift_lines(sp, offset_line)
            target.plans[-1] = with_sub_plans(target.plans[-1], value)
            continue
        previous = kind
        depth = nesting_depth(value)
        if depth > MAX_NESTING:  # before anything walks it (agentspeak/nesting.py says why)
            raise _BadInputAt(too_deep_message(), line)
        if kind == "belief":
            lit = value
            if not isinstance(lit, Literal):
                raise _BadInputAt(f"a belief must be a literal, not '{lit}'", line)
            if is_ground(lit):
                try:
                    target.beliefs.append(resolve(lit, {}))
                except ArithmeticError_ as exc:  # p(math.abs(a)).
                    raise _BadInputAt(f"in the belief {lit}: {exc}", line) from None
            else:
                target.rules.append(Rule(lit, Literal("true"), target.source_file, line + offset_line))
        elif kind == "rule":
            value.line += offset_line
            target.rules.append(value)
        elif kind == "goal":
            target.goals.append(value)
        elif kind == "plan":
            value.line += offset_line
            target.plans.append(value)
        elif kind == "directive":
            program_directive(target, value, line + offset_line)
        elif kind == "register_function":
            if value is not None:
                target.warnings.append(f"{program.source_file}:{line + offset_line}: {value}")
        elif kind == "begin":
            if not (isinstance(value, Literal) and value.functor in PATTERNS):
                raise _BadInputAt(_unknown_begin(value), line)
            blocks.append((value, line, target))
            target = Program(source_file=program.source_file)
        elif kind == "end":
            if not blocks:
                raise _BadInputAt("'{ end }' without a '{ begin ... }' before it", line)
            target = _end_block(blocks.pop(), target, offset_line)
    if blocks:
        directive, line, _ = blocks[-1]
        raise _BadInputAt(f"'{{ begin {directive if directive is not None else 'namespace(...)'} }}' has no "
                          f"'{{ end }}'", line)
    return scope


def _is_namespace_directive(value) -> bool:
    return isinstance(value, Literal) and value.functor == "namespace"


def _include_ns(lit: Literal, scope: NsScope | None) -> Literal:
    """``{ include("f.asl"[, NS]) }`` with its name space: the given atom, a new one for a variable
    (Jason: ``ns<N>``), else the current name space of the including file."""
    args = lit.args
    if len(args) >= 2:
        ns = args[1]
        if type(ns) is Var:
            ns = Literal(f"ns{unique_ns_id()}")
        elif not (type(ns) is Literal and not ns.args):
            raise _BadInput(f"the name space of {_shown(lit)} must be an atom or a variable")
        return Literal(lit.functor, (args[0], ns) + args[2:])
    current = scope.current if scope is not None else DEFAULT_NS_NAME
    return Literal(lit.functor, args + (Literal(current),)) if args else lit


def _unknown_begin(value) -> str:
    return f"unknown directive '{{ begin {value} }}'; expected one of {', '.join(PATTERNS)} (Jason's goal patterns)"


def _end_block(block: tuple, inner: Program, offset_line: int) -> Program:
    """``{ end }``: the pattern rewrites the block's clauses into the program around it."""
    directive, line, outer = block
    if inner.__dict__.get("includes"):
        raise _BadInputAt("an include inside '{ begin ... }' is not supported; include the file before it", line)
    try:
        made = apply_pattern(directive, inner, lambda text: _parse(text, inner.source_file, True)[0],
                             line + offset_line)
    except PatternError as exc:
        raise _BadInputAt(str(exc), line) from None
    outer.beliefs.extend(made.beliefs)
    outer.rules.extend(made.rules)
    outer.goals.extend(made.goals)
    outer.plans.extend(made.plans)
    outer.warnings.extend(made.warnings)
    return outer


def _shift_lines(plan: Plan, offset_line: int) -> None:
    plan.line += offset_line
    for sp in plan.sub_plans:
        _shift_lines(sp, offset_line)


def program_directive(program: Program, lit: Literal, line: int) -> None:
    if isinstance(lit, Literal) and lit.functor == "include" and lit.args and isinstance(lit.args[0], str):
        # where the directive stands: the included clauses go there, in source order (as Jason)
        at = (len(program.beliefs), len(program.rules), len(program.plans), len(program.goals))
        ns = lit.args[1].functor if len(lit.args) > 1 and isinstance(lit.args[1], Literal) else DEFAULT_NS_NAME
        program.__dict__.setdefault("includes", []).append((lit.args[0], line, at, ns))
    else:
        program.warnings.append(f"{program.source_file}:{line}: unknown directive '{lit}' ignored")


def _expand_includes(program: Program, source_file: str, base_dir: str | None, seen: set | None,
                     source_path: tuple = ()) -> Program:
    """Inline ``{ include("f.asl") }``: beside the including file, then along the source path
    (``agentspeak.sources``); a file already included is not included again."""
    from agentspeak.sources import find_source
    includes = program.__dict__.pop("includes", [])
    if not includes:
        return program
    seen = set() if seen is None else seen
    seen.add(os.path.abspath(source_file))
    base = base_dir or (os.path.dirname(source_file) if source_file and not source_file.startswith("<") else ".")
    inserted = [0, 0, 0, 0]  # clauses inserted so far into each list (the later positions move)
    for rel, line, at, ns in includes:
        path = find_source(rel, base, source_path)
        if path is None:
            where = ", ".join([base or "."] + list(source_path))
            raise AslSyntaxError(f"cannot include '{rel}': no such file (looked in {where})", source_file, line)
        once = os.path.abspath(path) if ns == DEFAULT_NS_NAME else (os.path.abspath(path), ns)
        if once in seen:  # a file is included once per name space (bob.asl includes a module twice)
            continue
        seen.add(once)
        try:
            text = read_source(path)
        except OSError as exc:
            raise AslSyntaxError(f"cannot include '{rel}': {exc.strerror or exc}", source_file, line) from exc
        except ValueError as exc:  # not UTF-8 (a SourceError), or a NUL byte in the path
            raise AslSyntaxError(f"cannot include {rel!r}: {exc}", source_file, line) from None
        sub = parse_program(text, path, os.path.dirname(path), seen, source_path, namespace=ns)
        for k, (target, items) in enumerate(((program.beliefs, sub.beliefs), (program.rules, sub.rules),
                                             (program.plans, sub.plans), (program.goals, sub.goals))):
            pos = at[k] + inserted[k]
            target[pos:pos] = items
            inserted[k] += len(items)
        program.warnings.extend(sub.warnings)
    return program


def _to_syntax_error(exc: Exception, full_text: str, text: str, source_file: str, offset_line: int) -> AslSyntaxError:
    lines = full_text.split("\n")
    if isinstance(exc, _BadInputAt):
        line = exc.line + offset_line
        src = lines[line - 1] if 0 < line <= len(lines) else None
        return AslSyntaxError(exc.message, source_file, line, None, src)
    line = getattr(exc, "line", None)
    column = getattr(exc, "column", None)
    if isinstance(exc, UnexpectedEOF) or line in (None, -1):
        # at end of input: point after the last non-blank character
        stripped = full_text.rstrip()
        line = stripped.count("\n") + 1
        column = len(stripped.split("\n")[-1]) + 1
        message = "unexpected end of file: " + _expected_text(getattr(exc, "expected", None) or [])
        if "." in _expected_text(getattr(exc, "expected", []) or []):
            message = "unexpected end of file: missing '.' at the end of the last clause?"
        return AslSyntaxError(message, source_file, line, column, lines[line - 1] if line <= len(lines) else None)
    line += offset_line
    src = lines[line - 1] if 0 < line <= len(lines) else None
    if isinstance(exc, UnexpectedCharacters):
        ch = text[exc.pos_in_stream] if exc.pos_in_stream < len(text) else ""
        if ch == '"':
            message = "unclosed string (a string must end with \" on the same line)"
        elif ch == "'":
            message = "unclosed quoted atom"
        else:
            allowed = getattr(exc, "allowed", None) or []
            message = f"unexpected character {ch!r}" + (f"; expected {_expected_text(allowed)}" if allowed else "")
        return AslSyntaxError(message, source_file, line, column, src)
    assert isinstance(exc, UnexpectedToken)
    tok = exc.token
    expected = set(exc.expected or ())
    if tok.type == "$END":
        stripped = full_text.rstrip()
        line = stripped.count("\n") + 1
        column = len(stripped.split("\n")[-1]) + 1
        src = stripped.split("\n")[-1]
        if "DOT" in expected:
            return AslSyntaxError("unexpected end of file: missing '.' at the end of the last clause",
                                  source_file, line, column, src)
        return AslSyntaxError("unexpected end of file; expected " + _expected_text(expected), source_file,
                              line, column, src)
    found = f"'{tok}'"
    if "DOT" in expected and tok.column == 1 or ("DOT" in expected and tok.type in ("PLUS", "MINUS", "AT", "BANG")):
        message = f"unexpected {found}: missing '.' at the end of the previous clause?"
    elif _unterminated_before(lines, line):
        # `... .print(a)` then `+!h <- ...` on the next line reads as `.print(a) + ...` up to the `!`
        return AslSyntaxError("missing '.' at the end of the previous clause?", source_file, line, 1, src)
    else:
        message = f"unexpected {found}; expected {_expected_text(expected)}"
    return AslSyntaxError(message, source_file, line, column, src)


def _unterminated_before(lines: list[str], line: int) -> bool:
    """The error's line starts a clause at column 1 (``+``, ``-``, ``@``, ``^``) and the previous
    non-blank line does not end one: the ``.`` is missing there, whatever token the parser stopped at."""
    if not (0 < line <= len(lines)) or not lines[line - 1][:1] in ("+", "-", "@", "^"):
        return False
    for prev in reversed(lines[:line - 1]):
        text = prev.split("//")[0].rstrip()
        if text:
            return not text.endswith((".", ";", "{", "(", "[", ",", "&", "|", "<-", ":", ":-"))
    return False


def _expected_text(expected) -> str:
    labels = sorted({TOKEN_LABELS.get(e, f"'{e}'" if len(e) <= 3 else e.lower()) for e in expected})
    if len(labels) > 8:
        labels = labels[:8] + ["..."]
    return "one of " + ", ".join(labels) if len(labels) > 1 else (labels[0] if labels else "nothing")


# -- single terms -----------------------------------------------------------------------------
def parse_literal(text: str) -> Term:
    """Parse one term, e.g. message content ``price(10)[a]`` (raises ``AslSyntaxError``).

    Ground terms (most message contents) are read by a small hand-written reader first."""
    term = read_ground_term(text)
    if term is not None:
        return term
    program = parse_program(f"term__({text}).", "<term>") if text.strip() else None
    if program is None:
        raise AslSyntaxError("empty term", "<term>", 1, 1, text)
    if program.beliefs:
        return program.beliefs[0].args[0]
    return program.rules[0].head.args[0]


def parse_term(text: str) -> Term:
    return parse_literal(text)


def parse_body(text: str) -> tuple:
    """Parse a plan body (used by ``.add_plan`` of strings and by tests)."""
    program = parse_program(f"+!body__ <- {text}.", "<body>")
    return program.plans[0].body


def parse_plans(text: str, source_file: str = "<string>") -> list[Plan]:
    return parse_program(text, source_file).plans


set_program_reader(parse_program)   # for .include (agentspeak/stdlib/system.py), without an import cycle
