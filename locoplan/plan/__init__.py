"""locoplan.plan"""
